# SPDX-License-Identifier: BSD-3-Clause
"""Vega FEM simulator configs from Python: the equivalent scene and what became of each key
(read_vega_config), and a config run as a scene."""
import json
import shutil

import numpy as np
import pytest

import asyncfem as af
from conftest import SOURCE_DIR

VEGA = SOURCE_DIR / "tests" / "data" / "vega"
FILES = ["cantilever.config", "bar.veg", "bar-root.bou", "bar-box.obj", "bar-box.interp"]


def test_the_equivalent_scene_and_the_key_table():
    config = af.read_vega_config(VEGA / "cantilever.config")
    scene = config["scene"]
    assert scene["mesh"] == {"file": "bar.veg"} and scene["fixed"] == {"bou": "bar-root.bou"}
    assert scene["integrator"]["name"] == "backward-euler" and scene["integrator"]["stepsPerFrame"] == 2
    assert scene["forceModel"] == {"type": "corotational", "tangent": "simple"}
    assert scene["gravity"] == [0.0, -9.81, 0.0]
    keys = {entry["key"]: entry for entry in config["keys"]}
    assert keys["cameraRadius"]["outcome"].startswith("ignored: interactive only")
    assert keys["dampingMassCoef"]["outcome"] == "damping.alpha = 0.1"
    assert keys["substepsPerTimeStep"]["line"] == 24
    assert config["secondary_rendering_mesh"].endswith("bar-box.obj") and config["rendering_mesh"] is None


def test_a_config_runs_as_its_equivalent_scene(tmp_path):
    for name in FILES:
        shutil.copy(VEGA / name, tmp_path / name)
    scene = tmp_path / "equivalent.json"
    scene.write_text(json.dumps(af.read_vega_config(tmp_path / "cantilever.config")["scene"], indent=2))
    from_config = af.run_scene(tmp_path / "cantilever.config", frames=2)
    from_json = af.run_scene(scene, frames=2)
    np.testing.assert_array_equal(from_config, from_json)  # one scene: the same run, bit for bit
    assert from_config[1].reshape(-1, 3)[8, 1] < 0  # gravity bends the free tip down


def test_an_unknown_key_is_a_parse_error_naming_file_and_line(tmp_path):
    bad = tmp_path / "bad.config"
    bad.write_text("# comment\n*volumetricMeshFilename\nbar.veg\n*cameraZoom\n2\n")
    with pytest.raises(af.ParseError, match=r"bad\.config:4: \*cameraZoom: unknown option"):
        af.read_vega_config(bad)
