"""The second run of a comparison, drawn in one browser's own scope of the scene as a
translucent tree and ROV that move with the replay it is compared with (the Record tab's
*Compare*).

The two runs are laid over each other at the moment the comparison aligns them
(``app.compare``'s ``Aligned``, on each run's own clock): at the replay's run time ``t`` the
ghost shows the second run's row at ``t - a_s + b_s``, held at its first or last row outside
it. Boxes of the set-up's tree and ROV sizes, not their meshes: a ghost says where the other
run was, and plain boxes keep it apart from the run shown.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from app.console import SceneInfo, quaternion_wxyz_from_rpy_radians

GHOST_ROOT = "/compare_ghost"
"""The ghost's nodes: ``/compare_ghost/tree`` and ``/compare_ghost/rov``."""
GHOST_TREE_COLOR = (190, 70, 230)
GHOST_ROV_COLOR = (150, 50, 200)
GHOST_OPACITY = 0.4
"""Purple, translucent: apart from the tree's own colours and the reference ghost's cyan."""


class Ghost:
    """Run B of a comparison in ``scene`` (a browser's ``client.scene``): ``t_s`` the run's
    own clock [s], ``tree`` and ``rov`` its (N, 6) poses, ``offset_s`` what to add to the
    shown run's time to get B's (``b_s - a_s`` of the alignment)."""

    def __init__(
        self,
        scene: Any,
        info: SceneInfo,
        t_s: np.ndarray,
        tree: np.ndarray,
        rov: np.ndarray,
        offset_s: float,
    ) -> None:
        self.t_s = np.asarray(t_s, float)
        self.tree = np.asarray(tree, float)
        self.rov = np.asarray(rov, float)
        self.offset_s = float(offset_s)
        self._root = scene.add_frame(GHOST_ROOT, show_axes=False)
        self.tree_node = scene.add_box(
            f"{GHOST_ROOT}/tree",
            color=GHOST_TREE_COLOR,
            dimensions=tuple(float(x) for x in info.tree_dimensions_m),
            opacity=GHOST_OPACITY,
            cast_shadow=False,
            receive_shadow=False,
        )
        self.rov_node = scene.add_box(
            f"{GHOST_ROOT}/rov",
            color=GHOST_ROV_COLOR,
            dimensions=tuple(float(x) for x in info.rov_dimensions_m),
            opacity=GHOST_OPACITY,
            cast_shadow=False,
            receive_shadow=False,
        )
        self._shown = -1

    @property
    def names(self) -> tuple[str, ...]:
        return (self.tree_node.name, self.rov_node.name)

    def index_at(self, run_t_s: float) -> int:
        """The row of run B shown when the replay's run is at ``run_t_s``."""
        k = int(np.searchsorted(self.t_s, run_t_s + self.offset_s + 1e-9, side="right")) - 1
        return int(np.clip(k, 0, len(self.t_s) - 1))

    def show(self, run_t_s: float) -> None:
        """Move the ghost to run B's pose at the replay's run time ``run_t_s``."""
        k = self.index_at(run_t_s)
        if k == self._shown:
            return
        self._shown = k
        tree, rov = self.tree[k], self.rov[k]
        self.tree_node.position = tree[0:3]
        self.tree_node.wxyz = quaternion_wxyz_from_rpy_radians(*tree[3:6])
        self.rov_node.position = rov[0:3]
        self.rov_node.wxyz = quaternion_wxyz_from_rpy_radians(*rov[3:6])

    def remove(self) -> None:
        self._root.remove()  # takes its children along
