"""The simulated station a ROS server drives one control period at a time: the MuJoCo task scene of a calibration,
its suction cup and blocks, and what happens to them (:class:`WorldEvent`).

:class:`TaskWorld` owns the scene (:func:`ur3hanoi.sim.build_task_scene`), the servo
(:class:`~ur3hanoi.sim.servo.JointServo`, the one servo law ``solve`` uses too), the suction cup
(:class:`ur3hanoi.sim.SuctionCup`: grasp by weld, ``gripper_input`` feedback) and the blocks (spawn, remove, drop
injection, where they are). Its subclasses say where each control period's joint reference comes from:
:class:`ur3hanoi.sim.world.MoveJWorld` (the course's ``movej`` commands) and
:class:`ur3hanoi.sim.servo_world.ServoWorld` (a streaming trajectory controller's targets, the official UR driver).
Nothing here knows ROS or the wall clock: the servers (:mod:`ur3hanoi.interface.common.station`) step a world once per
period in real time, tests as fast as they like.

Blocks are numbered from 0 here (0 = bottom/green); the ROS topics and the report number them from 1. Removed
blocks are parked on the floor beside the table ("off-grid"), so a respawn brings them back.
"""

from __future__ import annotations

from collections import Counter, deque
from dataclasses import dataclass
from typing import Any

import mujoco
import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.hanoi import block_colour
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.result import FinalBlock
from ur3hanoi.sim.scene import build_task_scene, slot_centers, start_slots
from ur3hanoi.sim.servo import JointServo
from ur3hanoi.sim.suction import GripperInput, SuctionCup
from ur3hanoi.sim.verify import at_home, locate_blocks
from ur3hanoi.station.calibration import Station

EVENTS_KEPT = 200
"""How many of the latest suction and block events the world keeps (a flood of commands toggling the suction must
not grow memory); :attr:`TaskWorld.event_counts` counts every event."""

@dataclass(frozen=True)
class WorldEvent:
    """Something that happened to the suction or the blocks: ``kind`` in {"suction_on", "suction_off", "grasp",
    "release", "spawn", "removed", "dropped"}; ``t`` [s] world time; ``block``/``tower`` 0-based or None."""

    t: float
    kind: str
    block: int | None = None
    tower: int | None = None

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"t": round(self.t, 4), "kind": self.kind}
        if self.block is not None:
            out["block"] = self.block + 1
            out["colour"] = block_colour(self.block)
        if self.tower is not None:
            out["tower"] = self.tower + 1
        return out


class TaskWorld:
    """The simulated arm, suction and blocks of a station (see the module docstring); a subclass drives the arm.

    Args:
        station: the calibration.
        start: tower (0-based) the blocks are spawned on, like the course's ``lab2_spawn.py``.
        n_blocks: number of blocks (1..station.n_heights).
        removed: height (0-based) left empty at spawn, or None.
        config: settings.
        drop_on_grasp: fault injection: the block of this grasp (0-based count of grasps) falls off
            ``config.drop_delay_s`` into the next motion, or None.
    """

    def __init__(self, station: Station, start: int, n_blocks: int, removed: int | None = None,
                 config: SimConfig | None = None, drop_on_grasp: int | None = None) -> None:
        self.config = cfg = config if config is not None else SimConfig()
        self.station = station
        if not 0 <= start < station.n_towers:
            raise SimulationError(f"start tower {start + 1} is invalid: expected 1..{station.n_towers}")
        if removed is not None and not 0 <= removed < n_blocks:
            raise SimulationError(f"removed block height {removed + 1} is invalid: expected 1..{n_blocks}")
        self.scene = build_task_scene(station, start, n_blocks, None, cfg.scene)
        m = self.scene.model
        self.servo = JointServo(self.scene, cfg.period_s, cfg.accel_feedforward)
        self.n_blocks = n_blocks
        self.cup = SuctionCup(self.scene, cfg.suction, seed=cfg.seed)
        self.events: deque[WorldEvent] = deque(maxlen=EVENTS_KEPT)  # the last ones; counts of all below
        self.event_counts: Counter[str] = Counter()
        self._centers = slot_centers(station)
        floor = m.geom("floor")
        floor_z = float(m.geom_pos[floor.id][2])
        s = station.block_size
        base = np.asarray(station.base_xyz, dtype=float)
        # Parking spots on the floor, 1 m beside the robot, away from the table (which spans the grid +- 0.15 m).
        self._park = {b: np.array([base[0] - 1.0, base[1] - 1.0 - 0.1 * b, floor_z + 0.5 * s]) for b in range(n_blocks)}
        self.removed: set[int] = set()
        self.servo.reset(station.q_home_array)
        self._grasps = 0
        self._drop_on_grasp = drop_on_grasp
        self._drop_armed = False
        self._attached: int | None = None
        self.spawn(start, removed)

    # ------------------------------------------------------------------------------------------------ state
    @property
    def time(self) -> float:
        """World (simulation) time [s]."""
        return float(self.scene.data.time)

    @property
    def q(self) -> FloatArray:
        """Measured joint angles [rad] (what the driver publishes)."""
        return self.scene.arm_q()

    @property
    def qd(self) -> FloatArray:
        """Measured joint velocities [rad/s]."""
        return self.scene.data.qvel[self.scene.arm_dadr].copy()

    @property
    def suction_on(self) -> bool:
        return self.cup.on

    @property
    def holding(self) -> int | None:
        """The block held by the suction (0-based), or None."""
        return self.cup.attached if self.cup.held() else None

    def feedback(self) -> GripperInput:
        """The suction feedback now (``DIGIN`` bit 0, ``AIN0`` [V] with seeded noise)."""
        return self.cup.feedback()

    def _event(self, event: WorldEvent) -> None:
        self.events.append(event)
        self.event_counts[event.kind] += 1

    # ------------------------------------------------------------------------------------------------ suction
    def set_suction(self, on: bool) -> None:
        """Switch the suction valve (no event when it already is so); turning it off releases any block."""
        if bool(on) == self.cup.on:
            return
        held = self.cup.attached
        self.cup.command(on)
        if on:
            self.cup.grasp_enabled = True
        self._event(WorldEvent(self.time, "suction_on" if on else "suction_off"))
        if not on and held is not None:
            self._event(WorldEvent(self.time, "release", held))
        self._attached = self.cup.attached

    def _update_suction(self, motion_s: float | None) -> None:
        """Once per control period before the physics: grasp a block in reach; drop an injected one
        ``drop_delay_s`` into the motion that follows its grasp (``motion_s``: time into the current motion [s],
        None at rest)."""
        self.cup.update()
        if self.cup.attached is not None and self._attached is None:
            self._event(WorldEvent(self.time, "grasp", self.cup.attached))
            if self._drop_on_grasp is not None and self._grasps == self._drop_on_grasp:
                self._drop_armed = True
            self._grasps += 1
        self._attached = self.cup.attached
        if self._drop_armed and motion_s is not None and motion_s >= self.config.drop_delay_s:
            self._drop_armed = False
            lost = self.cup.lose_block()
            self.cup.grasp_enabled = False  # a cup that lost its seal does not catch the falling block again
            self._attached = None
            if lost is not None:
                self._event(WorldEvent(self.time, "dropped", lost))

    # ------------------------------------------------------------------------------------------------ blocks
    def spawn(self, tower: int, removed: int | None = None) -> None:
        """Put every block on ``tower`` (0-based) like ``lab2_spawn.py``, leaving height ``removed`` empty.

        The suction lets go of any block first; a removed block is parked off-grid.
        """
        if not 0 <= tower < self.station.n_towers:
            raise SimulationError(f"tower {tower + 1} is invalid: expected 1..{self.station.n_towers}")
        if self.cup.attached is not None:
            self.cup.lose_block()
            self._attached = None
        slots = start_slots(self.station, tower, self.n_blocks, removed)
        self.removed = set(range(self.n_blocks)) - set(slots)
        for b in range(self.n_blocks):
            self.scene.place_block(b, self._centers[slots[b]] if b in slots else self._park[b])
        mujoco.mj_forward(self.scene.model, self.scene.data)
        self._event(WorldEvent(self.time, "spawn", tower=tower))
        for b in sorted(self.removed):
            self._event(WorldEvent(self.time, "removed", b))

    def remove(self, block: int) -> str:
        """Take ``block`` (0-based) away: park it off-grid; if the suction holds it, it is lost (a drop).

        Returns ``"removed"``, ``"dropped"`` (it was held) or ``"absent"`` (already removed).
        """
        if not 0 <= block < self.n_blocks:
            raise SimulationError(f"block {block + 1} is invalid: expected 1..{self.n_blocks}")
        if block in self.removed:
            return "absent"
        kind = "removed"
        if self.cup.attached == block:
            self.cup.lose_block()
            self._attached = None
            kind = "dropped"
        self.removed.add(block)
        self.scene.place_block(block, self._park[block])
        mujoco.mj_forward(self.scene.model, self.scene.data)
        self._event(WorldEvent(self.time, kind, block))
        return kind

    def blocks(self) -> tuple[FinalBlock, ...]:
        """Where every block is now: tower/height (0-based) of the slot within ``place_tolerance_m``, else None."""
        return locate_blocks(self.scene, self._centers, self.config.place_tolerance_m)

    def at_home(self) -> bool:
        """Every joint within ``home_tolerance_rad`` of the home pose."""
        return at_home(self.scene, self.config.home_tolerance_rad)
