"""The calibration plan and its design (paper §2.2–2.3, §3.4).

The plan itself (θ0, the identification order, the point sets, the fingerprint), the
planner's θ0 search and design, its steps, candidates, moves and tour, the joint
method's points, the wire's exit over a plan, and the plan from a pool of poses.
"""
