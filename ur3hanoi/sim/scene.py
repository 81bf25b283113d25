"""The station's task scene in MuJoCo: the UR3 at the calibrated base pose, a table, and the blocks.

:func:`build_task_spec` edits ``robots/universal_robots_ur3/scene.xml`` (robot, floor, light) with
:class:`mujoco.MjSpec`: the robot is placed at ``T_world_base * Rz(pi)`` (the URDF root ``base_link`` is the
controller ``base`` frame rotated by pi about z), the ``suction`` site is moved to the calibration's tool, a table
slab is added under the robot and every slot, and the blocks (green/yellow/red bottom to top, like the lab's
``lab2_spawn.py``) stand on the start tower, optionally with one block removed. Each block gets an inactive weld
equality to the suction cup (:mod:`ur3hanoi.sim.suction` switches it). :func:`build_task_scene` compiles it into a
:class:`TaskScene` holding the ids the executor needs.

Frames: MuJoCo's world is the station's world; MuJoCo's ``suction`` site equals
``T_world_base * Ur3Model.fk(q, "tcp")``. Towers, heights and blocks are 0-based.
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.hanoi import block_colour
from ur3hanoi.robot.model import T_BASELINK_BASE
from ur3hanoi.robot.urdf import JOINT_NAMES
from ur3hanoi.sim.model import SCENE_XML, T_ee_tcp, cup_geometry, quat_wxyz
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import block_center_world, table_z

BLOCK_RGBA: dict[str, tuple[float, float, float, float]] = {
    "green": (0.1, 0.7, 0.2, 1.0),
    "yellow": (0.95, 0.8, 0.1, 1.0),
    "red": (0.85, 0.1, 0.1, 1.0),
}
TABLE_THICKNESS = 0.04  # [m]


@dataclass(frozen=True)
class SceneConfig:
    """Task scene settings.

    Attributes:
        timestep: physics step [s]; 2 ms or less (the UR3 servo loop runs at 8 ms, 4 steps per cycle).
        block_mass: [kg], the lab's 1.25 in wooden cubes.
        friction: sliding friction of blocks and table: 0.5, the upper end of dry wood on wood (0.25-0.5, the
            usual handbook range). At 1.0 (rubber on wood) a block touching down while the cup still closed in on
            the vertical line (up to ~0.3 mm at 10-20 mm/s in the plan's last millimetre) did not slide on the
            stack's top but dragged it: the stack tilted ~0.05-0.1 deg and, released, sprang back and threw the top
            block 0.1-0.25 mm (measured, tall grid tower 3 height 6); 8 blocks on a tall grid (the other settings as
            now) ended with the top block over 5 mm off, failing the final check.
        weld_solref: (timeconst [s], dampratio) of the suction weld, i.e. how rigidly the cup holds the block.
            0.004 s, the stiffest stable at the 2 ms step (as for the contacts): a vacuum cup sealed on a flat face
            holds a 22.5 g block practically rigidly. At 0.01 s the block shifted 0.03-0.05 mm in the cup per move
            (pulled back by the stack at touch-down, sagging and swinging on the way), always the same way, and a
            grasp keeps the offset: 8 blocks on a tall grid (the other settings as now) drifted over 5 mm, failing the
            final check.
        noslip_iterations: MuJoCo's no-slip solver passes. Without them the soft contacts let a resting stack
            creep sideways (measured: the top of a 4-block stack slid 0.1-0.2 mm/s with nothing touching it), and
            since a grasp keeps the block's offset in the cup, the creep accumulated into 5-8 mm misplacements
            and a torn-off block on a 6-block tall grid. Wooden blocks do not creep: the no-slip pass removes it.
        contact_solref: (timeconst [s], dampratio) of the blocks' and the table's contacts. MuJoCo's default
            (0.02 s) lets each contact sink about 0.45 mm under a stack (2.3 mm for 6 blocks), so a block placed on
            a tall stack was pressed into it and sprang sideways when released (0.3-0.5 mm per release). 0.004 s,
            the stiffest stable at the 2 ms step (2 steps), keeps wooden blocks nearly rigid.
    """

    timestep: float = 0.002
    block_mass: float = 0.0225
    friction: float = 0.5
    weld_solref: tuple[float, float] = (0.004, 1.0)
    noslip_iterations: int = 10
    contact_solref: tuple[float, float] = (0.004, 1.0)


def slot_centers(station: Station) -> FloatArray:
    """Block centre of every slot, shape (n_towers, n_heights, 3) [m, world] (:func:`block_center_world`)."""
    return np.array([[block_center_world(station, t, h) for h in range(station.n_heights)]
                     for t in range(station.n_towers)])


def slot_of(centers: FloatArray, xyz: FloatArray, tolerance: float) -> tuple[int, int] | None:
    """The slot (tower, height), 0-based, whose block centre is nearest ``xyz`` [m, world], if within
    ``tolerance`` [m]; None when the block is in no slot. ``centers`` from :func:`slot_centers`."""
    dist = np.linalg.norm(centers - xyz, axis=-1)
    t, h = np.unravel_index(int(np.argmin(dist)), dist.shape)
    return (int(t), int(h)) if dist[t, h] <= tolerance else None


def block_name(block: int) -> str:
    """MuJoCo body name of block ``block`` (0-based, 0 = bottom/green)."""
    return f"block{block + 1}_{block_colour(block)}"


def start_slots(station: Station, start: int, n_blocks: int, removed: int | None = None) -> dict[int, tuple[int, int]]:
    """Initial (tower, height) of each present block (0-based), like the lab's ``lab2_spawn.py``.

    ``removed`` (0-based height) leaves that block out. Flat layout: its slot stays empty. Stacked layout: the
    blocks above it rest one level lower (they would fall there; spawning them there keeps the start calm).
    """
    slots: dict[int, tuple[int, int]] = {}
    level = 0
    for b in range(n_blocks):
        if b == removed:
            if station.layout == "flat":
                level += 1
            continue
        slots[b] = (start, level)
        level += 1
    return slots


def build_task_spec(station: Station, start: int, n_blocks: int, removed: int | None = None,
                    config: SceneConfig | None = None) -> mujoco.MjSpec:
    """``scene.xml`` + the robot at the station's base pose + table + blocks + one inactive suction weld per block.

    The ``suction`` site is moved to the station's tool offset, so it is the calibration's TCP exactly.
    """
    cfg = config if config is not None else SceneConfig()
    if station.robot.model_source == "dh":
        from ur3hanoi.sim.dh_model import build_dh_robot_spec

        spec = build_dh_robot_spec(station.robot)  # e.g. the UR3e: built from its description
    elif not SCENE_XML.is_file():
        raise SimulationError(f"{SCENE_XML} is missing: run python -m ur3hanoi.sim")
    else:
        spec = mujoco.MjSpec.from_file(str(SCENE_XML))
    spec.option.timestep = cfg.timestep
    spec.option.noslip_iterations = cfg.noslip_iterations
    if cfg.timestep > 0.002 + 1e-12:
        raise SimulationError(f"physics timestep {cfg.timestep} s is too long: expected <= 0.002 s")

    # Robot placement: T_world_baselink = T_world_base * T_base_baselink.
    T_wbl = station.T_world_base * T_BASELINK_BASE.inverse()
    base = spec.body("base_link")
    base.pos = T_wbl.translation
    base.quat = quat_wxyz(T_wbl.rotation)

    # Suction site = calibration TCP; cup geometry follows it.
    T_tcp = T_ee_tcp(station.tool)
    site = spec.site("suction")
    site.pos = T_tcp.translation
    site.quat = quat_wxyz(T_tcp.rotation)
    cup = cup_geometry(T_tcp)
    # Parsed back from the 12-digit text so that a task scene with the default tool equals ur3.xml exactly.
    spec.geom("suction_bracket").fromto = np.array([float(v) for v in cup["bracket"].split()])
    spec.geom("suction_cup").fromto = np.array([float(v) for v in cup["cup"].split()])

    # Table: a slab whose top is the grid's table surface, under the robot and every slot.
    tz = table_z(station)
    centers = slot_centers(station)
    pts = np.vstack([np.asarray(station.base_xyz)[:2], centers[..., :2].reshape(-1, 2)])
    lo, hi = np.min(pts, axis=0) - 0.15, np.max(pts, axis=0) + 0.15
    spec.worldbody.add_geom(
        name="table", type=mujoco.mjtGeom.mjGEOM_BOX,
        pos=[*(0.5 * (lo + hi)), tz - 0.5 * TABLE_THICKNESS],
        size=[*(0.5 * (hi - lo)), 0.5 * TABLE_THICKNESS],
        rgba=[0.55, 0.4, 0.28, 1.0], friction=[cfg.friction, 0.005, 0.0001], solref=list(cfg.contact_solref),
    )
    floor = spec.geom("floor")
    floor.pos = [0.0, 0.0, min(0.0, tz - TABLE_THICKNESS)]  # below the slab, never through it

    s = station.block_size
    slots = start_slots(station, start, n_blocks, removed)
    eq_data = np.zeros(mujoco.mjNEQDATA)
    eq_data[6] = 1.0  # identity relative quaternion; rewritten at run time before activation
    eq_data[10] = 1.0  # torquescale: the cup holds orientation as firmly as position
    for b, (t, h) in slots.items():
        body = spec.worldbody.add_body(name=block_name(b), pos=centers[t, h])
        body.add_freejoint(name=f"{block_name(b)}_free")
        body.add_geom(
            name=f"{block_name(b)}_geom", type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.5 * s] * 3,
            mass=cfg.block_mass, rgba=list(BLOCK_RGBA.get(block_colour(b), (0.3, 0.3, 0.9, 1.0))),
            friction=[cfg.friction, 0.005, 0.0001], solref=list(cfg.contact_solref),
        )
        spec.add_equality(
            name=f"suction_{block_name(b)}", type=mujoco.mjtEq.mjEQ_WELD, objtype=mujoco.mjtObj.mjOBJ_BODY,
            name1="suction_cup", name2=block_name(b), active=False, data=eq_data,
            solref=list(cfg.weld_solref),
        )

    # The robot-only keyframe has the wrong qpos size now: replace it by a full one (robot home, blocks spawned).
    for key in list(spec.keys):
        spec.delete(key)
    qpos = list(station.q_home)
    for t, h in slots.values():
        qpos += [*centers[t, h], 1.0, 0.0, 0.0, 0.0]
    spec.add_key(name="home", qpos=qpos, ctrl=list(station.q_home))
    return spec


@dataclass
class TaskScene:
    """A compiled task scene and the ids the executor needs."""

    station: Station
    spec: mujoco.MjSpec
    model: mujoco.MjModel
    data: mujoco.MjData
    n_blocks: int
    slots: dict[int, tuple[int, int]]  # initial (tower, height) of each present block
    site_id: int
    cup_body: int
    block_body: dict[int, int]  # block -> body id
    block_eq: dict[int, int]  # block -> weld equality id
    block_qadr: dict[int, int]  # block -> qpos address of its free joint
    arm_qadr: npt.NDArray[np.int_]
    arm_dadr: npt.NDArray[np.int_]

    def site_pose(self) -> pin.SE3:
        """The suction site (TCP) in world."""
        d = self.data
        return pin.SE3(d.site_xmat[self.site_id].reshape(3, 3).copy(), d.site_xpos[self.site_id].copy())

    def block_pos(self, block: int) -> FloatArray:
        """Centre of ``block`` [m, world]."""
        return self.data.xpos[self.block_body[block]].copy()

    def arm_q(self) -> FloatArray:
        """The six arm joint angles [rad]."""
        return self.data.qpos[self.arm_qadr].copy()

    def place_block(self, block: int, xyz: FloatArray) -> None:
        """Put ``block`` with its centre at ``xyz`` [m, world], upright and at rest (by hand: run
        :func:`mujoco.mj_forward` before reading positions)."""
        adr = self.block_qadr[block]
        self.data.qpos[adr:adr + 3] = xyz
        self.data.qpos[adr + 3:adr + 7] = (1.0, 0.0, 0.0, 0.0)
        dof = int(self.model.jnt_dofadr[self.model.body_jntadr[self.block_body[block]]])
        self.data.qvel[dof:dof + 6] = 0.0


def build_task_scene(station: Station, start: int, n_blocks: int, removed: int | None = None,
                     config: SceneConfig | None = None) -> TaskScene:
    """Compile :func:`build_task_spec` and reset it to the ``home`` keyframe."""
    if not 1 <= n_blocks <= station.n_heights:
        raise SimulationError(f"{n_blocks} blocks is invalid: expected 1..{station.n_heights}")
    spec = build_task_spec(station, start, n_blocks, removed, config)
    try:
        model = spec.compile()
    except ValueError as exc:
        raise SimulationError(f"the MuJoCo task scene does not compile: {exc}") from None
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, model.key("home").id)
    mujoco.mj_forward(model, data)
    slots = start_slots(station, start, n_blocks, removed)
    jids = [model.joint(j).id for j in JOINT_NAMES]
    return TaskScene(
        station=station, spec=spec, model=model, data=data, n_blocks=n_blocks, slots=slots,
        site_id=model.site("suction").id, cup_body=model.body("suction_cup").id,
        block_body={b: model.body(block_name(b)).id for b in slots},
        block_eq={b: model.equality(f"suction_{block_name(b)}").id for b in slots},
        block_qadr={b: int(model.jnt_qposadr[model.joint(f"{block_name(b)}_free").id]) for b in slots},
        arm_qadr=np.array([model.jnt_qposadr[j] for j in jids]),
        arm_dadr=np.array([model.jnt_dofadr[j] for j in jids]),
    )


def warning_counts(data: mujoco.MjData) -> dict[str, int]:
    """Non-zero MuJoCo warning counters (``data.warning``) by name."""
    out = {}
    for name, w in mujoco.mjtWarning.__members__.items():
        if name == "mjNWARNING":
            continue
        n = int(data.warning[int(w)].number)
        if n:
            out[name] = n
    return out
