"""Every benchmark script still imports: a bench names modules and functions of the package
that may move or go, and a bench nobody runs in the suite broke unseen once (bench_twin
imported a function that had left app.compare)."""

from __future__ import annotations

import importlib.util

import pytest

from .conftest import ROOT

BENCHES = sorted((ROOT / "bench").glob("bench_*.py"))


def test_there_are_benches():
    assert len(BENCHES) >= 10, [p.name for p in BENCHES]


@pytest.mark.parametrize("path", BENCHES, ids=lambda p: p.stem)
def test_a_bench_imports(path, monkeypatch):
    monkeypatch.syspath_prepend(str(path.parent))  # as when run: its folder is on the path
    spec = importlib.util.spec_from_file_location(f"bench_import_{path.stem}", path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # defines its functions; main() runs only as a script
    assert callable(getattr(module, "main", None)), f"{path.name} has no main()"
