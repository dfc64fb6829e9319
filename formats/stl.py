"""STL meshes (binary or ASCII): their vertices, for the link radii of a URDF import."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from wirecal.solver.errors import WirecalError

MAX_STL_BYTES = 64 * 1024 * 1024
"""Largest mesh read (bytes): a robot link's collision mesh is 10 kB–5 MB."""

_HEADER = 80
_FACET = 50  # normal, three vertices (12 float32) and a 2-byte attribute
_VERTEX = re.compile(rb"^[ \t]*vertex\b([^\r\n]*)", re.M)


def stl_vertices(path: Path) -> np.ndarray:
    """Return the vertices (k, 3) of an STL file, in its own units.

    Binary when the size is 84 + 50 × the facet count in its header, ASCII otherwise.
    Raise :class:`WirecalError` naming the file when it is unreadable, too large, empty or
    holds a non-finite coordinate.
    """
    try:
        size = path.stat().st_size
        if size > MAX_STL_BYTES:
            raise WirecalError(f"{path}: larger than {MAX_STL_BYTES // 2**20} MB: not read")
        data = path.read_bytes()
    except OSError as exc:
        raise WirecalError(f"{path}: cannot read the mesh: {exc.strerror or exc}") from None
    count = int.from_bytes(data[_HEADER : _HEADER + 4], "little") if len(data) >= 84 else -1
    if len(data) == _HEADER + 4 + _FACET * count:
        facets = np.frombuffer(
            data[_HEADER + 4 :], dtype=np.dtype([("f", "<f4", (12,)), ("a", "<u2")])
        )
        points = facets["f"][:, 3:].reshape(-1, 3).astype(float)
    else:
        rows = [line.split() for line in _VERTEX.findall(data)]
        try:
            if any(len(r) != 3 for r in rows):
                raise ValueError
            points = np.array([[float(x) for x in r] for r in rows]).reshape(-1, 3)
        except ValueError:
            raise WirecalError(f"{path}: an ASCII STL vertex is not three numbers") from None
    if not len(points):
        raise WirecalError(f"{path}: no vertices (neither a binary nor an ASCII STL)")
    if not np.all(np.isfinite(points)):
        raise WirecalError(f"{path}: a vertex is not finite")
    return points
