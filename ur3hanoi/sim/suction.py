"""The lab's vacuum gripper, emulated: suction on/off, grasping by weld equality, and the ``gripper_input`` feedback.

:class:`SuctionCup` follows the course's Gazebo plugin rule adapted to a weld: when the suction is on and the
suction point is within ``grasp_radius`` of where it would be at contact with a block, that block's weld equality
(added by :func:`ur3hanoi.sim.build_task_spec`) is activated at the current relative pose. :class:`GripperInput`
is the emulated ``ur3/gripper_input`` sample (``DIGIN`` bit 0 = block held, ``AIN0`` [V], seeded noise), at the
levels of a :class:`~ur3hanoi.station.suction_profile.SuctionProfile`: the station calibration's (``suction:`` section;
the course simulator's levels by default) unless :class:`SuctionConfig` gives one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import mujoco
import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.sim.scene import TaskScene
from ur3hanoi.station.suction_profile import SuctionProfile


@dataclass(frozen=True)
class SuctionConfig:
    """Emulated vacuum gripper (the course's Gazebo plugin rule, adapted to a weld).

    Attributes:
        grasp_radius: a block is grasped when suction is on and the suction point is within this distance [m] of
            the block's expected suction point at contact: top-face centre minus ``contact_depth`` along world z
            (the lab rule: within 0.01 m of the grasp point; measured against the contact point because the
            calibrations put the suction point ``contact_depth`` below the top face).
        hold_tolerance: a welded block counts as held while the weld is stretched less than this [m]: the
            distance of the block's centre from where the weld holds it (its pose in the cup when grasped). A
            block grasped off-centre (anywhere within ``grasp_radius``) is held as firmly as a centred one; only a
            weld stretched further means the block is being torn off.
        profile: the feedback levels (``DIGIN``, ``AIN0`` held / cup free / off); None: the station's
            (``Station.suction``, from the calibration's ``suction`` section).
        ain_noise: standard deviation [V] of the seeded Gaussian noise on ``AIN0``; None: the profile's.
    """

    grasp_radius: float = 0.01
    hold_tolerance: float = 0.01
    profile: SuctionProfile | None = None
    ain_noise: float | None = None


@dataclass(frozen=True)
class GripperInput:
    """One ``ur3/gripper_input`` sample: ``DIGIN`` bit 0 = block held, ``AIN0`` [V], at sim time ``t`` [s]."""

    t: float
    digin: int
    ain0: float

    @property
    def held(self) -> bool:
        return bool(self.digin & 1)


class SuctionCup:
    """Suction on/off, grasping by weld equality, drop injection and the ``gripper_input`` feedback."""

    def __init__(self, scene: TaskScene, config: SuctionConfig | None = None, seed: int = 0) -> None:
        self.scene = scene
        self.config = config if config is not None else SuctionConfig()
        profile = self.config.profile if self.config.profile is not None else scene.station.suction
        self.profile: SuctionProfile = profile
        self._noise = profile.ain0_noise if self.config.ain_noise is None else self.config.ain_noise
        self.rng = np.random.default_rng(seed)
        self.on = False
        self.attached: int | None = None
        self._rel_pos = np.zeros(3)  # block centre in the cup frame when grasped [m]
        self.grasp_enabled = True  # cleared while halting: a faulted cup must not pick anything up
        st = scene.station
        # Block centre -> suction point at contact; constant, and read every control cycle by held().
        self._contact_offset = np.array([0.0, 0.0, 0.5 * st.block_size - st.contact_depth])
        m = scene.model
        for eq in scene.block_eq.values():
            m.eq_data[eq, 11] = 0.0  # use the relative pose written below, not one computed from qpos0

    def expected_suction_point(self, block: int) -> FloatArray:
        """Where the suction point sits at contact with ``block``: top-face centre minus contact_depth [m, world]."""
        return self.scene.block_pos(block) + self._contact_offset

    def command(self, on: bool) -> None:
        """Set the suction valve (``io_0``); turning it off releases any block."""
        if not on and self.attached is not None:
            self._detach()
        self.on = bool(on)

    def update(self) -> None:
        """Grasp the nearest block within ``grasp_radius`` when on and empty (called every control cycle)."""
        if not self.on or self.attached is not None or not self.grasp_enabled:
            return
        p_cup = self.scene.data.site_xpos[self.scene.site_id]
        best, best_d = None, self.config.grasp_radius
        for b in self.scene.block_body:
            d = float(np.linalg.norm(self.expected_suction_point(b) - p_cup))
            if d <= best_d:
                best, best_d = b, d
        if best is not None:
            self._attach(best)

    def _attach(self, block: int) -> None:
        # Write the current relative pose (block in cup) before activating, or the weld pulls the block by
        # the stale offset.
        d, m = self.scene.data, self.scene.model
        c, k = self.scene.cup_body, self.scene.block_body[block]
        R_c = d.xmat[c].reshape(3, 3)
        rel_pos = R_c.T @ (d.xpos[k] - d.xpos[c])
        conj_c, rel_quat = np.empty(4), np.empty(4)
        mujoco.mju_negQuat(conj_c, d.xquat[c])
        mujoco.mju_mulQuat(rel_quat, conj_c, d.xquat[k])
        eq = self.scene.block_eq[block]
        m.eq_data[eq, 0:3] = 0.0
        m.eq_data[eq, 3:6] = rel_pos
        m.eq_data[eq, 6:10] = rel_quat
        d.eq_active[eq] = 1
        self.attached = block
        self._rel_pos = rel_pos.copy()

    def _detach(self) -> None:
        assert self.attached is not None
        self.scene.data.eq_active[self.scene.block_eq[self.attached]] = 0
        self.attached = None

    def lose_block(self) -> int | None:
        """Fault injection: the seal breaks and the held block falls while the suction stays on."""
        block = self.attached
        if block is not None:
            self._detach()
        return block

    def stretch(self) -> float:
        """How far [m] the held block's centre is from where the weld holds it (0 when nothing is held)."""
        if self.attached is None:
            return 0.0
        d = self.scene.data
        c = self.scene.cup_body
        held_at = d.xpos[c] + d.xmat[c].reshape(3, 3) @ self._rel_pos
        off = self.scene.block_pos(self.attached) - held_at
        return math.sqrt(float(off.dot(off)))  # np.linalg.norm's arithmetic, without its per-call overhead

    def held(self) -> bool:
        if not self.on or self.attached is None:
            return False
        return self.stretch() <= self.config.hold_tolerance

    def feedback(self) -> GripperInput:
        """The emulated ``gripper_input`` now, at the profile's levels (seeded noise on ``AIN0``)."""
        digin, volts = self.profile.levels(self.held(), self.on)
        volts += float(self.rng.normal(0.0, self._noise)) if self._noise > 0 else 0.0
        return GripperInput(t=float(self.scene.data.time), digin=digin, ain0=volts)
