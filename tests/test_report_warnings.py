"""``report`` states the warnings ``solve`` states (one source: ``app.gate.warnings``)."""

from __future__ import annotations

import numpy as np
import pytest
from click.testing import CliRunner

from wirecal.cli.main import main
from wirecal.formats.simulated_log import simulate_log
from wirecal.solver.run_parameters import PAPER_RUN
from wirecal.solver.simulate import realistic_encoder

from .conftest import VIPER


def _warnings(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if line.startswith("warning: ")]


@pytest.mark.slow
def test_report_states_the_drift_warning_solve_states(viper, paper_plan, tmp_path):
    """A linear 2 mm/h drift at the paper's speed is measured to ±0.2 mm/h: removed from
    the lengths, and beyond the 0.5 mm/h tolerance a warning to fix the stand. ``report``
    used to print only the unchecked items and the accepted findings, never this."""
    rng = np.random.default_rng(1)
    errors = {n: float(rng.uniform(-1, 1)) for n in viper.parameters}
    encoder = realistic_encoder(viper.encoder, rng, zero_drift_mm_per_h=2.0)
    log = tmp_path / "run.csv"
    log.write_text(simulate_log(viper, paper_plan, errors, seed=1, encoder=encoder, run=PAPER_RUN))
    robot, plan = str(VIPER / "robot.toml"), str(VIPER / "paper_plan.toml")
    solved = CliRunner().invoke(main, ["solve", robot, plan, str(log)])
    reported = CliRunner().invoke(
        main, ["report", robot, plan, str(log), "-o", str(tmp_path / "r.html")]
    )
    assert solved.exit_code == 0, solved.output
    assert reported.exit_code == 0, reported.output
    drift = [w for w in _warnings(solved.stderr) if "the zero readings drift by +" in w]
    assert len(drift) == 1, solved.stderr
    assert "it was removed from the lengths" in drift[0]
    assert _warnings(reported.stderr) == _warnings(solved.stderr)
