"""The scene's meshes (web.meshes) are the parameter set's bodies: the tree fills its box, the
funnels' mouths sit on its bottom over the docking layout's posts, the docking frame spans its
size and the post tops, the ROV fills its drawing box with a duct per thruster of the
allocation's configuration, where that configuration puts it."""

from __future__ import annotations

import numpy as np
import pytest

from app.console.snapshot import scene_info
from sim import params
from sim.docking import DockingFrame
from web import meshes

PRESETS = ("model-scale", "full-scale")
TOL_M = 1e-9
"""Bounding boxes are built from the dimensions themselves: equal to rounding."""


@pytest.fixture(scope="module", params=PRESETS)
def info(request: pytest.FixtureRequest):
    ps = params.load(request.param)
    frame = DockingFrame(np.zeros(2), 0.0, 100.0)
    return scene_info(ps, frame, 1)


def _tree(info) -> meshes.Parts:
    lay = info.layout
    return meshes.tree_parts(
        np.array(info.tree_dimensions_m),
        lay.post_xy_m,
        lay.funnel_mouth_radius_m,
        lay.funnel_bore_radius_m,
        lay.funnel_cone_height_m,
    )


def test_the_tree_fills_its_box(info) -> None:
    half = np.array(info.tree_dimensions_m) / 2.0
    bounds = meshes.combined(_tree(info)).bounds
    np.testing.assert_allclose(bounds, [-half, half], atol=TOL_M)


def test_a_funnel_over_each_post_its_mouth_on_the_tree_bottom(info) -> None:
    lay = info.layout
    parts = _tree(info)
    funnels = [parts[name] for name in sorted(parts) if name.startswith("funnel_")]
    assert len(funnels) == len(lay.post_xy_m)
    height = info.tree_dimensions_m[2]
    wall = 0.1 * lay.funnel_bore_radius_m
    for funnel, (x, y) in zip(funnels, lay.post_xy_m, strict=True):
        lo, hi = funnel.bounds
        # round to the facets: the lathe's polygon sits inside the circle
        mouth = lay.funnel_mouth_radius_m + wall
        np.testing.assert_allclose(0.5 * (lo[:2] + hi[:2]), [x, y], atol=1e-3 * mouth)
        np.testing.assert_allclose(0.5 * (hi[:2] - lo[:2]), [mouth, mouth], rtol=0.01)
        assert hi[2] == pytest.approx(0.5 * height)  # the mouth on the bottom (z down)


def test_the_running_tool_reaches_the_attachment_point(info) -> None:
    height = info.tree_dimensions_m[2]
    bounds = meshes.combined(meshes.running_tool_parts(height, info.attachment_height_m)).bounds
    assert bounds[1, 2] == pytest.approx(-0.5 * height)
    assert bounds[0, 2] == pytest.approx(-info.attachment_height_m)


def test_the_docking_frame_spans_its_size_and_the_post_tops(info) -> None:
    lay = info.layout
    depth = 0.3
    parts = meshes.docking_frame_parts(
        lay.frame_size_m, lay.post_xy_m, lay.post_radius_m, lay.post_height_m, depth
    )
    lo, hi = meshes.combined(parts).bounds
    np.testing.assert_allclose(hi - lo, [*lay.frame_size_m, lay.post_height_m + depth], atol=TOL_M)
    assert lo[2] == pytest.approx(-lay.post_height_m)
    posts = [parts[n] for n in sorted(parts) if n.startswith("post_")]
    assert len(posts) == len(lay.post_xy_m)
    for post, (x, y) in zip(posts, lay.post_xy_m, strict=True):
        np.testing.assert_allclose(post.bounds.mean(axis=0)[:2], [x, y], atol=1e-3)


def test_the_rov_fills_its_box_with_a_duct_per_thruster(info) -> None:
    size = np.array(info.rov_dimensions_m)
    t = np.array(info.thruster_configuration).T
    parts = meshes.rov_parts(size, t)
    np.testing.assert_allclose(meshes.combined(parts).bounds, [-size / 2, size / 2], atol=TOL_M)
    ducts = [name for name in parts if name.startswith("thruster_")]
    assert len(ducts) == info.n_thrusters == t.shape[1]


def test_thrusters_stand_where_the_configuration_puts_them(info) -> None:
    """Each drawn thruster gives back its column of T: direction d, and the moment r x d
    (up to the part along d no place gives, and the spread of twin columns, whose pair
    gives the same summed moment)."""
    size = np.array(info.rov_dimensions_m)
    t = np.array(info.thruster_configuration).T
    poses = meshes.thruster_poses_b(t, size)
    moments = np.cross(poses[:, 0:3], poses[:, 3:6])
    for i in range(t.shape[1]):
        d = t[0:3, i] / np.linalg.norm(t[0:3, i])
        np.testing.assert_allclose(poses[i, 3:6], d, atol=1e-12)
        m_perp = t[3:6, i] - (t[3:6, i] @ d) * d
        inside = np.all(np.abs(poses[i, 0:3]) < size / 2)
        assert inside
        twins = [j for j in range(t.shape[1]) if np.allclose(t[:, j], t[:, i])]
        summed = moments[twins].sum(axis=0) / len(twins)
        clipped = np.any(
            np.abs(np.cross(t[0:3, i], t[3:6, i])) / (t[0:3, i] @ t[0:3, i])
            > size / 2 - 1.2 * meshes.thruster_duct_radius_m(size)
        )
        if not clipped:  # a place the ROV's box holds is the configuration's own
            np.testing.assert_allclose(summed * np.linalg.norm(t[0:3, i]), m_perp, atol=1e-9)


def test_meshes_face_outwards(info) -> None:
    """Every round part has its faces outwards (a lathe profile turned the wrong way shows
    the inside in the browser): volume positive on the merged mesh."""
    parts = _tree(info)
    for name, part in parts.items():
        merged = part.copy()
        merged.merge_vertices()
        assert merged.volume > 0.0, name
