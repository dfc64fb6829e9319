"""Ψ (paper eq. 16–17): the projection of Φ_{i−0} on the wire direction, in mm/deg for
angles and mm/mm for lengths — the first-order change of the wire length."""

from __future__ import annotations

import numpy as np

from wirecal.solver.distance import wire_lengths
from wirecal.solver.sensitivity import sensitivity


def test_psi_is_phi_diff_projected_and_the_wire_length_derivative(viper, paper_plan):
    q, _, _ = paper_plan.all_points()
    names = paper_plan.order
    s = sensitivity(viper.nominal, q, paper_plan.theta0_deg, names)
    np.testing.assert_allclose(np.einsum("nk,nkm->nm", s.nu_hat, s.phi_diff), s.psi)
    np.testing.assert_allclose(np.linalg.norm(s.nu_hat, axis=1), 1.0)
    base = wire_lengths(viper.nominal, np.radians(q), np.radians(paper_plan.theta0_deg))
    for k, name in enumerate(names):
        h = 1e-4  # deg or mm: Ψ is per degree / per mm
        moved = wire_lengths(
            viper.model({name: h}), np.radians(q), np.radians(paper_plan.theta0_deg)
        )
        np.testing.assert_allclose((moved - base) / h, s.psi[:, k], atol=2e-4, err_msg=name)
