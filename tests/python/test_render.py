# SPDX-License-Identifier: BSD-3-Clause
"""Off-screen rendering from Python (module built with ASYNCFEM_WITH_RENDER)."""
import numpy as np
import pytest

import asyncfem as af
from conftest import small_box


def test_render_mesh_to_array_and_png(tmp_path):
    assert af.has_render
    mesh = small_box()
    renderer = af.OffscreenRenderer(64, 48, supersampling=1)
    assert (renderer.width, renderer.height, renderer.supersampling) == (64, 48, 1)
    style = af.RenderStyle()
    style.background = [1.0, 1.0, 1.0]
    image = renderer.render_mesh(mesh, style=style)
    assert image.shape == (48, 64, 3) and image.dtype == np.uint8
    assert (image[0, 0] == 255).all()  # background in a corner (the fitted camera leaves a margin)
    assert (image != 255).any(axis=2).sum() > 100  # the box covers pixels
    again = renderer.render_mesh(mesh, style=style)
    np.testing.assert_array_equal(image, again)  # deterministic
    moved = renderer.render_mesh(mesh, 0.05 * np.ones(mesh.num_dofs), camera=af.fit_camera(af.bounding_box(mesh), 64 / 48),
                                 style=style)
    assert not np.array_equal(moved, image)
    red = np.tile([1.0, 0.0, 0.0], (mesh.num_vertices, 1))
    tinted = renderer.render_mesh(mesh, style=style, colors=red)
    covered = (tinted != 255).any(axis=2)
    assert (tinted[covered][:, 0].astype(int) >= tinted[covered][:, 2]).all()  # red wins where drawn

    path = tmp_path / "frame.png"
    af.write_png(path, image)
    np.testing.assert_array_equal(af.read_png(path), image)  # PNG is lossless
    with pytest.raises(ValueError, match=r"image: expected a uint8 array of shape \(height, width, 3\)"):
        af.write_png(path, image.astype(np.float64))


def test_render_surfaces_and_ground():
    triangle = af.Surface(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]), np.array([[0, 1, 2]]))
    style = af.RenderStyle()
    style.ground = af.GroundPlane(center=[0.0, -0.1, 0.0], half_size=2.0, tile_size=0.25)
    camera = af.Camera(position=[0.3, 0.3, 3.0], target=[0.3, 0.3, 0.0])
    image = af.OffscreenRenderer(32, 32, 1).render([triangle], camera, style)
    assert image.shape == (32, 32, 3)
    with pytest.raises(af.Error):
        af.OffscreenRenderer(0, 10)
    with pytest.raises(ValueError, match="triangles: expected an integer array"):
        af.Surface(np.zeros((3, 3)), np.zeros((1, 3)))
