"""Path counts per kind in the reports: PO scattering centres apart from point targets."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from raysim.echoes.po.paths import PO_CENTRE
from raysim.echoes.rt.trace import DIFFRACTION, DIFFUSE, SENSING, SPECULAR
from raysim.pipeline.sources import path_kinds


def test_path_kinds_counts_every_po_centre_and_each_point_target_once():
    """One point target and three PO centres of a mesh are 1 target and 3 PO centres."""
    kind = np.array([SPECULAR, DIFFUSE, DIFFUSE | SPECULAR, SENSING, PO_CENTRE, PO_CENTRE,
                     PO_CENTRE, SPECULAR | DIFFRACTION], dtype=np.uint32)
    assert path_kinds(SimpleNamespace(kind=kind)) == {
        "specular": 1, "diffuse": 2, "target": 1, "po_centre": 3, "other_specular": 1}
