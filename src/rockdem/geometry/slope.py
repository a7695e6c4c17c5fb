"""The generated geometry: blocks, joint table and joint lines, ready for a Model."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import shapely

from ..blocks import Blocks
from ..interfaces import Interfaces, assign_joints, find_interfaces
from ..joints import Joint
from ..model import Loads, Model, Settings
from .joint_sets import JointSet
from .profile import Profile

__all__ = ["Sliver", "SlopeGeometry"]


@dataclass(frozen=True)
class Sliver:
    """A block found smaller than ``min_block_fraction`` x the typical block.

    Attributes
    ----------
    area : float
        Its area when found.
    centroid : (x, y)
        Where it was.
    action : {"merged", "kept", "removed"}
        Merged into the neighbour sharing the longest edge, kept (it could
        not be merged, or merging was not asked for), or removed (a small
        piece left by an excavation).
    block : int or None
        Id of the block it now belongs to (None if removed).
    """

    area: float
    centroid: tuple[float, float]
    action: str
    block: int | None


@dataclass(frozen=True, eq=False)
class SlopeGeometry:
    """A cut slope section: what :func:`generate_slope` and the editors return.

    Attributes
    ----------
    blocks : rockdem.Blocks
        Free blocks (ids 0, 1, ... by centroid: columns of equal x left to
        right, each bottom to top) then the fixed ground blocks.
    joints : tuple of Joint
        Joint table: one per joint set (renamed to the set's name), then
        ``"bridge"`` (if any set is non-persistent), then ``"ground"`` (if a
        ground joint was given), then joints of added blocks.
    joint_lines : ndarray, shape (m, 2, 2)
        Joint traces of every set first, then the rock-bridge stretches.
    line_joint : ndarray of int, shape (m,)
        Index into ``joints`` of every line.
    ground : int or None
        Index into ``joints`` of the ground contact (None: ground contacts
        take the joint of the trace they lie on, else ``joints[0]``).
    section : shapely.Polygon
        The section cut into blocks (without the fixed boundary strips).
    slivers : tuple of Sliver
        Small blocks found and what was done with them.
    profile : Profile or None
    joint_sets : tuple of JointSet
    typical_area : float
        Median area of the free blocks when generated (the sliver yardstick).
    min_block_fraction : float
    """

    blocks: Blocks
    joints: tuple[Joint, ...]
    joint_lines: np.ndarray
    line_joint: np.ndarray
    ground: int | None
    section: shapely.Polygon
    slivers: tuple[Sliver, ...] = ()
    profile: Profile | None = None
    joint_sets: tuple[JointSet, ...] = ()
    typical_area: float = float("nan")
    min_block_fraction: float = 0.05
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    # ----------------------------------------------------------- engine
    def model(
        self,
        loads: Loads | None = None,
        settings: Settings | None = None,
        name: str = "slope",
    ) -> Model:
        """The engine model of this geometry."""
        return Model(
            self.blocks,
            self.joints,
            joint_lines=self.joint_lines if len(self.joint_lines) else None,
            line_joint=tuple(int(v) for v in self.line_joint) if len(self.joint_lines) else None,
            ground=self.ground,
            loads=Loads() if loads is None else loads,
            settings=Settings() if settings is None else settings,
            name=name,
        )

    def interfaces(self) -> Interfaces:
        """Interfaces between the blocks with their joint index (as the engine assigns them)."""
        if "faces" not in self._cache:
            faces = find_interfaces(self.blocks)
            lines = self.joint_lines if len(self.joint_lines) else None
            self._cache["faces"] = assign_joints(
                faces, self.blocks, default=0, ground=self.ground, lines=lines,
                line_joint=self.line_joint if lines is not None else None,
            )
        return self._cache["faces"]

    def interface_types(self) -> np.ndarray:
        """Name of the joint of every interface: a set name, ``"bridge"`` or ``"ground"``."""
        names = np.array([j.name for j in self.joints], dtype=object)
        return names[self.interfaces().joint]

    def length_by_type(self) -> dict[str, float]:
        """Total interface length per joint name."""
        faces = self.interfaces()
        names = [j.name for j in self.joints]
        tot = np.bincount(faces.joint, faces.length, minlength=len(names))
        out: dict[str, float] = {}
        for k, nm in enumerate(names):
            out[nm] = out.get(nm, 0.0) + float(tot[k])
        return out

    # ------------------------------------------------------------ views
    @property
    def line_names(self) -> np.ndarray:
        """Joint name of every joint line (set name or ``"bridge"``)."""
        names = np.array([j.name for j in self.joints], dtype=object)
        return names[self.line_joint] if len(self.line_joint) else np.zeros(0, dtype=object)

    @property
    def free(self) -> np.ndarray:
        """Ids of the free blocks."""
        return self.blocks.ids[~self.blocks.fixed]

    def polygons(self) -> np.ndarray:
        """The blocks as shapely Polygons (block order)."""
        return self.blocks.polygons()

    def replace(self, **changes) -> SlopeGeometry:
        """A copy with some fields changed (caches dropped)."""
        changes.setdefault("_cache", {})
        return replace(self, **changes)

    def __repr__(self) -> str:
        b = self.blocks
        return (
            f"<SlopeGeometry: {b.n_blocks - int(b.fixed.sum()):,} free blocks, "
            f"{int(b.fixed.sum())} ground blocks, {len(self.joint_sets)} joint sets, "
            f"{len(self.joint_lines):,} joint lines, {len(self.slivers)} slivers>"
        )
