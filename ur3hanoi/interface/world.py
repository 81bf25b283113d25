"""The station's physical side: the MuJoCo task scene of a calibration driven like the UR controller drives the arm.

:class:`StationWorld` owns the scene (:func:`ur3hanoi.sim.build_task_scene`), the suction cup
(:class:`ur3hanoi.sim.SuctionCup`: grasp by weld, ``gripper_input`` feedback) and the blocks. Each :meth:`step`
advances one control period: the reference of the running ``movej`` (:mod:`ur3hanoi.robot.movej`) is sent to the
position servos with velocity feed-forward (as :func:`ur3hanoi.sim.run_plan` does), the physics runs, the suction
grasps a block in reach. Nothing here knows ROS or the wall clock: the node (:mod:`ur3hanoi.interface.ros1.server`)
calls
:meth:`step` once per period in real time, tests call it as fast as they like.

Blocks are numbered from 0 here (0 = bottom/green); the ROS topics and the report number them from 1. Removed
blocks are parked on the floor beside the table ("off-grid"), so a respawn brings them back.
"""

from __future__ import annotations

from collections import Counter, deque
from dataclasses import dataclass, field
from typing import Any

import mujoco
import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import block_colour
from ur3hanoi.interface.command import MoveCommand
from ur3hanoi.interface.errors import RosError
from ur3hanoi.robot.model import JOINT_NAMES
from ur3hanoi.robot.movej import MoveJ, plan_movej
from ur3hanoi.sim import (
    FinalBlock,
    GripperInput,
    SceneConfig,
    SuctionConfig,
    SuctionCup,
    build_task_scene,
    slot_centers,
    slot_of,
    start_slots,
)
from ur3hanoi.station.calibration import Station

EVENTS_KEPT = 200
"""How many of the latest suction and block events the world keeps (a flood of commands toggling the suction must
not grow memory); :attr:`StationWorld.event_counts` counts every event."""


@dataclass(frozen=True)
class WorldConfig:
    """Settings of the simulated station.

    Attributes:
        period_s: control period [s]; a multiple of the physics step. 8 ms: the CB3 controller's 125 Hz (the
            course driver publishes ``ur3/position`` every 8 ms).
        settle_tolerance_rad: the arm is "at" its destination when every joint is within this angle [rad] (the
            lab's ``move_arm`` waits for 0.0005 rad).
        scene, suction: see :class:`ur3hanoi.sim.SceneConfig`, :class:`ur3hanoi.sim.SuctionConfig`.
        seed: seeds the ``AIN0`` noise.
        place_tolerance_m: a block is in a slot when its centre is within this distance [m] of the slot's centre.
        home_tolerance_rad: "at home" when every joint is within this angle [rad] of the home pose.
        drop_delay_s: with a drop injected on a grasp, the block falls this long [s] into the next motion.
    """

    period_s: float = 0.008
    settle_tolerance_rad: float = 5e-4
    scene: SceneConfig = field(default_factory=SceneConfig)
    suction: SuctionConfig = field(default_factory=SuctionConfig)
    seed: int = 0
    place_tolerance_m: float = 0.005
    home_tolerance_rad: float = 0.01
    drop_delay_s: float = 0.2


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


class StationWorld:
    """The simulated UR3 station (see the module docstring).

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
                 config: WorldConfig | None = None, drop_on_grasp: int | None = None) -> None:
        self.config = cfg = config if config is not None else WorldConfig()
        self.station = station
        if not 0 <= start < station.n_towers:
            raise RosError(f"start tower {start + 1} is invalid: expected 1..{station.n_towers}")
        if removed is not None and not 0 <= removed < n_blocks:
            raise RosError(f"removed block height {removed + 1} is invalid: expected 1..{n_blocks}")
        self.scene = build_task_scene(station, start, n_blocks, None, cfg.scene)
        m = self.scene.model
        self.nsub = round(cfg.period_s / m.opt.timestep)
        if self.nsub < 1 or abs(self.nsub * m.opt.timestep - cfg.period_s) > 1e-9:
            raise RosError(f"control period {cfg.period_s} s is invalid: expected a multiple of the physics step "
                           f"{m.opt.timestep} s")
        self.n_blocks = n_blocks
        self._act = np.array([m.actuator(j.removesuffix("_joint")).id for j in JOINT_NAMES])
        kp = m.actuator_gainprm[self._act, 0]
        kv = -m.actuator_biasprm[self._act, 2]
        self._ff = kv / kp  # velocity feed-forward [s]: servo force kp (q_ref - q) + kv (qd_ref - qd)
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
        self.reference: FloatArray = station.q_home_array.copy()  # the servo reference at the end of the last step
        self.target: FloatArray = self.reference.copy()  # destination of the current (or last) move
        self.motion: MoveJ | None = None
        self._t_motion = 0.0  # time into the current motion [s]
        self._servo_prev = self.reference.copy()
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
        """Measured joint angles [rad] (what ``ur3/position`` publishes)."""
        return self.scene.arm_q()

    @property
    def moving(self) -> bool:
        """True while a ``movej`` profile runs."""
        return self.motion is not None

    def error_to_target(self) -> float:
        """Largest joint distance [rad] between the measured angles and the current destination."""
        return float(np.max(np.abs(self.q - self.target)))

    @property
    def settled(self) -> bool:
        """No profile running and every joint within ``settle_tolerance_rad`` of the destination."""
        return self.motion is None and self.error_to_target() <= self.config.settle_tolerance_rad

    @property
    def suction_on(self) -> bool:
        return self.cup.on

    @property
    def holding(self) -> int | None:
        """The block held by the suction (0-based), or None."""
        return self.cup.attached if self.cup.held() else None

    def feedback(self) -> GripperInput:
        """The ``gripper_input`` now (``DIGIN`` bit 0, ``AIN0`` [V] with seeded noise)."""
        return self.cup.feedback()

    def _event(self, event: WorldEvent) -> None:
        self.events.append(event)
        self.event_counts[event.kind] += 1

    # ------------------------------------------------------------------------------------------------ motion
    def begin(self, command: MoveCommand) -> MoveJ:
        """Switch the suction to ``command.io_0`` and start its ``movej`` from the current reference."""
        if command.io_0 != self.cup.on:
            self._suction(command.io_0)
        lim = self.station.limits
        self.motion = plan_movej(self.reference, command.destination, command.v, command.a, lim.v_max, lim.a_max)
        self.target = self.motion.q1.copy()
        self._t_motion = 0.0
        motion = self.motion
        if motion.duration <= 0.0:
            self.motion = None
            self.reference = motion.q1.copy()
        return motion

    def _suction(self, on: bool) -> None:
        held = self.cup.attached
        self.cup.command(on)
        if on:
            self.cup.grasp_enabled = True
        self._event(WorldEvent(self.time, "suction_on" if on else "suction_off"))
        if not on and held is not None:
            self._event(WorldEvent(self.time, "release", held))
        self._attached = self.cup.attached

    def step(self) -> None:
        """Advance one control period: servo reference, physics, suction grasp, injected drop."""
        d, m = self.scene.data, self.scene.model
        if self.motion is not None:
            self._t_motion += self.config.period_s
            q_ref, qd_ref = self.motion.sample(self._t_motion)
            if self._t_motion >= self.motion.duration:
                self.motion = None
        else:
            q_ref, qd_ref = self.reference, np.zeros_like(self.reference)
        self.reference = q_ref
        servo = q_ref + self._ff * qd_ref
        # The mean of the (linear) servo command over the period: holding the end value would lead by a period.
        d.ctrl[self._act] = 0.5 * (self._servo_prev + servo)
        self._servo_prev = servo
        self.cup.update()
        if self.cup.attached is not None and self._attached is None:
            self._event(WorldEvent(self.time, "grasp", self.cup.attached))
            if self._drop_on_grasp is not None and self._grasps == self._drop_on_grasp:
                self._drop_armed = True
            self._grasps += 1
        self._attached = self.cup.attached
        if self._drop_armed and self.motion is not None and self._t_motion >= self.config.drop_delay_s:
            self._drop_armed = False
            lost = self.cup.lose_block()
            self.cup.grasp_enabled = False  # a cup that lost its seal does not catch the falling block again
            self._attached = None
            if lost is not None:
                self._event(WorldEvent(self.time, "dropped", lost))
        mujoco.mj_step(m, d, nstep=self.nsub)

    # ------------------------------------------------------------------------------------------------ blocks
    def _set_block(self, block: int, xyz: FloatArray) -> None:
        d = self.scene.data
        adr = self.scene.block_qadr[block]
        d.qpos[adr:adr + 3] = xyz
        d.qpos[adr + 3:adr + 7] = (1.0, 0.0, 0.0, 0.0)
        dof = int(self.scene.model.jnt_dofadr[self.scene.model.body_jntadr[self.scene.block_body[block]]])
        d.qvel[dof:dof + 6] = 0.0

    def spawn(self, tower: int, removed: int | None = None) -> None:
        """Put every block on ``tower`` (0-based) like ``lab2_spawn.py``, leaving height ``removed`` empty.

        The suction lets go of any block first; a removed block is parked off-grid.
        """
        if not 0 <= tower < self.station.n_towers:
            raise RosError(f"tower {tower + 1} is invalid: expected 1..{self.station.n_towers}")
        if self.cup.attached is not None:
            self.cup.lose_block()
            self._attached = None
        slots = start_slots(self.station, tower, self.n_blocks, removed)
        self.removed = set(range(self.n_blocks)) - set(slots)
        for b in range(self.n_blocks):
            self._set_block(b, self._centers[slots[b]] if b in slots else self._park[b])
        mujoco.mj_forward(self.scene.model, self.scene.data)
        self._event(WorldEvent(self.time, "spawn", tower=tower))
        for b in sorted(self.removed):
            self._event(WorldEvent(self.time, "removed", b))

    def remove(self, block: int) -> str:
        """Take ``block`` (0-based) away: park it off-grid; if the suction holds it, it is lost (a drop).

        Returns ``"removed"``, ``"dropped"`` (it was held) or ``"absent"`` (already removed).
        """
        if not 0 <= block < self.n_blocks:
            raise RosError(f"block {block + 1} is invalid: expected 1..{self.n_blocks}")
        if block in self.removed:
            return "absent"
        kind = "removed"
        if self.cup.attached == block:
            self.cup.lose_block()
            self._attached = None
            kind = "dropped"
        self.removed.add(block)
        self._set_block(block, self._park[block])
        mujoco.mj_forward(self.scene.model, self.scene.data)
        self._event(WorldEvent(self.time, kind, block))
        return kind

    def blocks(self) -> tuple[FinalBlock, ...]:
        """Where every block is now: tower/height (0-based) of the slot within ``place_tolerance_m``, else None."""
        out = []
        tol = self.config.place_tolerance_m
        for b in range(self.n_blocks):
            xyz = self.scene.block_pos(b)
            slot = slot_of(self._centers, xyz, tol)
            out.append(FinalBlock(b, None if slot is None else slot[0], None if slot is None else slot[1],
                                  (float(xyz[0]), float(xyz[1]), float(xyz[2]))))
        return tuple(out)

    def at_home(self) -> bool:
        return bool(np.max(np.abs(self.q - self.station.q_home_array)) <= self.config.home_tolerance_rad)
