# SPDX-License-Identifier: BSD-3-Clause
"""examples/python/parameter_sweep.py (needs rendering) writes its contact sheet."""
import numpy as np

import asyncfem as af
from test_examples import run


def test_parameter_sweep(tmp_path):
    output = tmp_path / "sweep.png"
    text = run("parameter_sweep.py", "--small", "--output", output, cwd=tmp_path)
    assert "3 stiffnesses x 3 times" in text
    sheet = af.read_png(output)
    assert sheet.shape == (3 * 72, 3 * 96, 3)
    tiles = [sheet[r * 72:(r + 1) * 72, c * 96:(c + 1) * 96] for r in range(3) for c in range(3)]
    assert all((tile != 255).any() for tile in tiles)  # every tile shows the beam
    assert not np.array_equal(tiles[1], tiles[4])  # different stiffness, same time: different shape
