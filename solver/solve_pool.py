"""The estimate ``wirecal solve`` gives for a plan from a pool: the fit the plan was made for.

``wirecal plan --pool`` chooses θ0 and the poses for one wire's fit with a prior where the
readings are weak (:mod:`~wirecal.solver.wire_prior`): the anchor, one length offset, the
attachment, every DH error of rows 2…n and the robot file's ``[calibration] compliances``,
each DH error and compliance with a zero-mean prior, soft-L1 loss. ``solve`` runs that
fit (:func:`~wirecal.solver.wire_prior.fit_wire`, the one the tracker replay scores), not
the joint method on the file's ``[calibration] parameters``: here it becomes the joint
estimate of a :class:`~wirecal.solver.solve.SolveResult`, its σ the posterior's, and the
budget's map and shares (:class:`~wirecal.solver.budget.PriorTerms`).

The anchor and the offset are the fit's own (the wire's fixed end, anywhere; the zero):
reported, not part of the patch. Every other parameter is one a patch holds by name.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from wirecal.solver.budget import PriorTerms
from wirecal.solver.fit.calibrate import point_model
from wirecal.solver.fit.model import geometry_jacobian
from wirecal.solver.identifiability import std_and_correlation
from wirecal.solver.identify import Estimate
from wirecal.solver.plan.options import PlanOptions
from wirecal.solver.robot import Robot
from wirecal.solver.wire_prior import Posterior, WireMap, fit_wire, posterior

LOG_JOINT_RESOLUTION_DEG = 1e-4
"""The log's joints carry four decimals (:func:`~wirecal.formats.log.format_row`): the
joints' share of the readings' floor."""


@dataclass(frozen=True)
class PriorFit:
    """How a plan from a pool was solved: the prior, what the readings carry, the anchor."""

    prior_sd: dict[str, float]  # each estimated parameter's prior σ, boundary units
    prior_mm: float  # the prior's size the evidence chose (a length's σ, mm)
    effective: float  # parameters the readings carry, of all fitted (trace of the hat)
    fitted: int  # every parameter fitted: the estimate's, the anchor (3), the offset
    anchor_mm: np.ndarray  # (3,) the wire's fixed end, base frame
    offset_mm: float  # the length at zero distance less the zero reading
    # (N, m) ∂L/∂e of the estimate's parameters, boundary units, the anchor's and the
    # offset's columns projected out: what the readings say of e once those are fitted
    jacobian: np.ndarray

    def as_json(self) -> dict[str, Any]:
        """Return the fit's description for ``wirecal solve --json``."""
        return {
            "fit": "one wire with a prior where the readings are weak (plan from a pool)",
            "prior_std": dict(self.prior_sd),
            "prior_mm": self.prior_mm,
            "effective_parameters": self.effective,
            "fitted_parameters": self.fitted,
            "anchor_mm": self.anchor_mm.tolist(),
            "offset_mm": self.offset_mm,
        }


@dataclass(frozen=True)
class PoolSolution:
    """The joint estimate of a plan from a pool, how it was fitted, the budget's terms."""

    estimate: Estimate
    fit: PriorFit
    terms: PriorTerms
    sigma_mm: float  # the readings' σ on N − effective degrees of freedom


def pool_estimate(robot: Robot, q_deg: np.ndarray, length_mm: np.ndarray) -> PoolSolution:
    """Fit the readings ``length_mm`` at ``q_deg`` as the pool plan intends (module docstring)."""
    wm, data = fit_wire(
        robot,
        robot.compliances,
        q_deg,
        length_mm,
        PlanOptions.prior,
        LOG_JOINT_RESOLUTION_DEG,
    )
    post = posterior(point_model(robot), wm, data)
    g = len(wm.layout.geometry)
    per = wm.layout.boundary_per_internal
    cov = (post.noise + post.prior_share)[:g, :g] * np.outer(per[:g], per[:g])
    std, corr = std_and_correlation(cov)
    residual = float(np.sqrt(np.mean(post.residual_mm**2)))
    estimate = Estimate("joint", wm.layout.geometry, wm.x[:g] * per[:g], residual, std, corr)
    return PoolSolution(estimate, _prior_fit(wm, post), _terms(post, g), post.sigma_mm)


def _prior_fit(wm: WireMap, post: Posterior) -> PriorFit:
    """Return the :class:`PriorFit` of ``wm`` and its posterior."""
    layout, g = wm.layout, len(wm.layout.geometry)
    per = layout.boundary_per_internal
    _, anchor, _, offsets = layout.split(wm.x)
    J = geometry_jacobian(post.jacobian, g)
    return PriorFit(
        dict(zip(layout.geometry, (post.prior_sd * per)[:g].tolist(), strict=True)),
        wm.prior,
        post.effective,
        len(layout.names),
        anchor.copy(),
        float(offsets[0]),
        J / per[:g],
    )


def _terms(post: Posterior, g: int) -> PriorTerms:
    """Return the budget's terms: the posterior's rows of the estimate's ``g`` parameters."""
    return PriorTerms(post.map[:g], post.noise[:g, :g], post.prior_share[:g, :g])
