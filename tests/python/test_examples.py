# SPDX-License-Identifier: BSD-3-Clause
"""Each example of examples/python runs (small sizes) and writes what it says it writes."""
import os
import subprocess
import sys

import numpy as np

import asyncfem as af
from conftest import SOURCE_DIR

EXAMPLES = SOURCE_DIR / "examples" / "python"


def run(name, *args, cwd):
    result = subprocess.run([sys.executable, str(EXAMPLES / name), *map(str, args)], cwd=cwd, env=dict(os.environ),
                            capture_output=True, text=True, timeout=240)
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_default_scene(tmp_path):
    output = tmp_path / "beam.afsim"
    text = run("default_scene.py", "--frames", 6, "--output", output, cwd=tmp_path)
    assert "6 frames" in text
    reader = af.SimulationReader(output)
    assert reader.num_frames == 6 and reader.header.frame_interval == 1 / 30
    displacements = reader.displacements()
    assert np.isfinite(displacements).all() and displacements[-1].reshape(-1, 3)[:, 1].min() < 0  # pulled down


def test_async_vs_single_rate(tmp_path):
    output = tmp_path / "tip.png"
    text = run("async_vs_single_rate.py", "--seconds", 0.05, "--output", output, cwd=tmp_path)
    assert text.count("s wall") == 3
    if af.has_render:
        image = af.read_png(output)
        assert image.shape == (450, 800, 3)  # figsize 8 x 4.5 at dpi 100
    else:
        assert output.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_custom_load(tmp_path):
    text = run("custom_load.py", "--frames", 4, "--output", tmp_path / "gust", cwd=tmp_path)
    assert "evaluated 32 times" in text  # 4 frames x 8 steps, one call per backward Euler step
    assert (tmp_path / "gust" / "frames.pvd").exists() and (tmp_path / "gust" / "frame_00003.vtu").exists()


def test_help_describes_each_example_in_whole_sentences(tmp_path):
    """--help gives the docstring's whole first paragraph, not its first line cut mid-sentence."""
    for name in ("default_scene.py", "async_vs_single_rate.py", "custom_load.py", "parameter_sweep.py"):
        text = run(name, "--help", cwd=tmp_path)
        description = " ".join(text.split("\n\n")[1].split())
        assert description.endswith("."), (name, description)
        first_line = (EXAMPLES / name).read_text().split('"""')[1].splitlines()[0]
        assert description.startswith(first_line) and len(description) > len(first_line), (name, description)
