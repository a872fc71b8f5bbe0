"""Underwater light and silt (web.underwater), pure: contact with the frame or the seabed,
the silt cloud a touch raises (thinned to 2 % after a minute), the visibility inside it, the
fog's distances and the water's colour, and the sonar's echoes at their range and bearing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.console import VISIBILITY_MAX_M, VISIBILITY_MIN_M
from app.console.snapshot import scene_info
from sim import params
from sim.docking import DockingFrame
from web import underwater as uw


@pytest.fixture(scope="module")
def info():
    frame = DockingFrame(np.array([0.0, 0.0]), 0.0, 100.0)
    return scene_info(params.load("model-scale"), frame, 1, frame_in_mission=True)


def _tree_at(info, bottom_depth_m: float, north_m: float = 0.0) -> np.ndarray:
    return np.array([north_m, 0.0, bottom_depth_m - 0.5 * info.tree_dimensions_m[2], 0, 0, 0])


def _rov_away(info) -> np.ndarray:
    return np.array([0.0, -5.0, 90.0, 0.0, 0.0, 0.0])


def test_contact_on_the_post_tops_the_landing_surface_and_the_seabed(info) -> None:
    tops = info.frame.post_top_depth_m(info.layout)
    hanging = uw.contact_points_n(info, _tree_at(info, tops - 0.3), _rov_away(info))
    assert len(hanging) == 0
    # funnels 0.12 m off their posts (the tolerance is 0.10 m): the skirts land on the tops
    on_posts = uw.contact_points_n(info, _tree_at(info, tops, 0.12), _rov_away(info))
    assert len(on_posts) == 1 and on_posts[0][2] == pytest.approx(tops)
    # captured, the posts go into the funnels: no contact until the landing surface
    passing = uw.contact_points_n(info, _tree_at(info, tops + 0.1), _rov_away(info))
    assert len(passing) == 0
    landed = uw.contact_points_n(info, _tree_at(info, info.frame.landing_depth_m), _rov_away(info))
    assert len(landed) == 1
    off = uw.contact_points_n(info, _tree_at(info, uw.seabed_depth_m(info), 10.0), _rov_away(info))
    assert len(off) == 1, "the tree on the seabed beside the frame"
    rov = np.array([0.0, -5.0, uw.seabed_depth_m(info) - 0.5 * info.rov_dimensions_m[2], 0, 0, 0])
    assert len(uw.contact_points_n(info, _tree_at(info, tops - 0.3), rov)) == 1


def test_a_touch_raises_a_cloud_that_thins_out_over_a_minute(info) -> None:
    touch = np.array([[0.0, 0.0, 100.0]])
    none = np.zeros((0, 3))
    state = uw.next_silt(uw.SiltState(), info, 10.0, none)
    assert state.cloud is None
    state = uw.next_silt(state, info, 11.0, touch)
    cloud = state.cloud
    assert cloud is not None and cloud.start_t_s == 11.0
    assert cloud.density(11.0) == 1.0
    assert cloud.density(11.0 + 60.0) == pytest.approx(math.exp(-4.0))  # 1.8 % after a minute
    resting = uw.next_silt(state, info, 30.0, touch)
    assert resting.cloud is cloud, "a body at rest raises no new cloud"
    assert uw.next_silt(resting, info, 72.0, touch).cloud is None, "gone after a minute"
    assert uw.next_silt(resting, info, 5.0, none).cloud is None, "a replay turned back"


def test_visibility_in_the_cloud_and_the_fog(info) -> None:
    cloud = uw.SiltCloud(np.array([0.0, 0.0, 100.0]), 0.0, 1.0)
    size = uw.tree_size_m(info)
    inside = uw.silt_visibility_m(20.0, cloud, 0.0, np.array([0.0, 0.0, 99.8]), size)
    assert inside == pytest.approx(uw.SILT_VISIBILITY_SIZES * size)
    far = uw.silt_visibility_m(20.0, cloud, 0.0, np.array([10.0, 0.0, 100.0]), size)
    assert far == 20.0
    later = uw.silt_visibility_m(20.0, cloud, 45.0, np.array([0.0, 0.0, 99.8]), size)
    assert inside < later <= 20.0
    assert uw.fog_range_m(10.0) == (1.0, 10.0)
    assert uw.fog_range_m(10.0, standoff_m=15.0) == (16.0, 25.0)
    assert uw.water_rgb(VISIBILITY_MAX_M) == tuple(uw.CLEAR_WATER_RGB.astype(int))
    assert uw.water_rgb(VISIBILITY_MIN_M) == tuple(uw.TURBID_WATER_RGB.astype(int))


def test_sonar_echo_at_the_trees_range_and_bearing(info) -> None:
    """The tree 5 m ahead of the ROV (and 30 deg to starboard in a second picture): its echo
    is the brightest part of the picture there, and the picture is noise elsewhere."""
    reach = uw.sonar_range_m(info)
    half = uw.SONAR_PX / 2
    for bearing_deg in (0.0, 30.0):
        b = math.radians(bearing_deg)
        rov = np.array([0.0, 0.0, 95.0, 0.0, 0.0, 0.0])
        tree = np.array([5.0 * math.cos(b), 5.0 * math.sin(b), 95.6, 0.0, 0.0, 0.0])
        img = uw.sonar_image(info, rov, tree, np.random.default_rng(1)).astype(float)
        assert img.shape == (uw.SONAR_PX, uw.SONAR_PX, 3)
        near = 4.5 * half / reach  # the tree's near face, in pixels from the middle
        x = int(half + near * math.sin(b))
        y = int(half - near * math.cos(b))
        echo = img[y - 3 : y + 4, x - 3 : x + 4, 0].max()
        assert echo > 150.0, (bearing_deg, echo)
        assert np.median(img[..., 0]) < 60.0
