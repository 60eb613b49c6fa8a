"""The loop's grid in C (amr_twin/sim/grid_steps.c) against its Python twin (the grid loop of
Twin._step_physics): the same bits through a drive with a payload, a collision and a stop on
collision, with every instant's samplers; MuJoCo's errors become exceptions."""

import ctypes
import functools
import shutil
from types import SimpleNamespace

import mujoco
import numpy as np
import pytest

import amr_twin.sim.grid_steps as grid_steps
import amr_twin.sim.grid_loop as grid_loop_mod
from amr_twin.model.config import load_config
from amr_twin.sim.grid_rows import GridRows, gather
from amr_twin.sim.grid_steps import grid_stepper
from amr_twin.assembly.twin import Twin, TwinOptions
from amr_twin.base.native_build import address, mujoco_address
from amr_twin.recording.recorder import attach_recorder, recorder_of

pytestmark = pytest.mark.skipif(
    shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler"
)
HEAVY_REAR = load_config(overrides={"payload.mass_kg": 40.0, "payload.xy_m": [-0.2, 0.05]})


def _run(monkeypatch, native: bool, options: TwinOptions, script, cfg=None):
    """The twin of ``options`` driven by ``script``, with a support sampler (50 Hz), its grid in C
    or in Python; what it ends with, and how often the C grid ran and handed an instant back."""
    monkeypatch.setattr(
        grid_loop_mod, "grid_stepper", functools.partial(grid_stepper, native=native)
    )
    calls = {"runs": 0, "handoffs": 0}
    real = grid_steps.GridStepper.run

    def run(self, *args):
        reached, handoff = real(self, *args)
        calls["runs"] += 1
        calls["handoffs"] += handoff >= 0
        return reached, handoff

    monkeypatch.setattr(grid_steps.GridStepper, "run", run)
    twin = Twin(cfg or load_config(), options)
    attach_recorder(twin)
    support = twin.rolling.support_rows(20_000)
    twin.samplers.append(support)
    script(twin)
    d, s = twin.physics.data, recorder_of(twin).series()
    state = {
        "qpos": d.qpos.copy(),
        "qvel": d.qvel.copy(),
        "time": d.time,
        "t_phys_us": twin.t_phys_us,
        "halted": twin.halted,
        "soc": twin.plant.battery.soc,
        "t_s": s.t_s,
        "rows": support.take(),
        "angle": s.wheel_angle_rad,
        "rpm": s.true_rpm,
        "pose": s.pose,
        "pwm": s.pwm_counts,
        "current": s.current_a,
        "battery": (s.battery_v, s.battery_a, s.battery_soc),
        "published": [s.published[w] for w in sorted(s.published)],
        "collisions": twin.collisions.as_dicts(),
        "friction": twin.physics.model.dof_frictionloss.copy(),
    }
    return state, calls


def _same(a: dict, b: dict) -> None:
    for key in a:
        if key in ("collisions", "halted"):
            assert a[key] == b[key], key
        elif key == "published":
            assert len(a[key]) == len(b[key]) and all(
                np.array_equal(x, y) for x, y in zip(a[key], b[key])
            ), key
        else:
            assert np.array_equal(np.asarray(a[key]), np.asarray(b[key])), key


def _veer_and_spin(twin):
    twin.client.linear(0.7)
    twin.advance(8.5)  # veers into the rack south of the aisle (test_collisions)
    twin.client.angular(90.0, 0.0)
    twin.advance(1.5)


@pytest.mark.parametrize("payload", ["none", "heavy at the rear"])
def test_the_grid_in_c_gives_the_python_loops_bits_through_a_collision(monkeypatch, payload):
    """The veering run that scrapes a rack (without a payload; with 40 kg at the rear it passes),
    then a spin: the state, the record, the published speeds, the support samples, the battery
    and the episodes are the same to the bit; the C grid ran and handed instants back (the
    contacts changing, the support rows outgrowing their room)."""
    cfg = HEAVY_REAR if payload != "none" else load_config()
    options = TwinOptions(start_xy_yaw=None, visuals=False)
    c_state, c_calls = _run(monkeypatch, True, options, _veer_and_spin, cfg)
    py_state, py_calls = _run(monkeypatch, False, options, _veer_and_spin, cfg)
    assert py_calls["runs"] == 0 and c_calls["runs"] > 50 and c_calls["handoffs"] >= 3
    assert len(c_state["rows"]) == 500
    if payload == "none":
        assert c_state["collisions"] and c_state["collisions"][0]["hit"] == "rack_s_beam_low"
    _same(c_state, py_state)


def test_a_stop_on_collision_halts_both_at_the_same_instant(monkeypatch):
    options = TwinOptions(start_xy_yaw=None, visuals=False, stop_on_collision=True)

    def drive(twin):
        twin.client.linear(0.7)
        twin.advance(9.0)

    c_state, c_calls = _run(monkeypatch, True, options, drive)
    py_state, _ = _run(monkeypatch, False, options, drive)
    assert c_state["halted"] and c_calls["handoffs"] >= 1
    assert 6.0 < c_state["t_phys_us"] * 1e-6 < 8.0
    _same(c_state, py_state)


def test_rows_kept_in_c_are_the_python_rows():
    """GridRows: the C row keeper (the C grid) and the Python row (the Python loop) keep the same
    values at the same instants, through two growths of its room; the last row is the physics
    as the run ends (loads, contact forces, tilt cosine, base velocity, in that order)."""
    out = []
    for in_c in (True, False):
        twin = Twin(HEAVY_REAR, TwinOptions(world="empty", visuals=False))
        support = twin.rolling.support_rows(30_000)
        if not in_c:  # the same row in Python only: the twin's grid runs in Python
            support = GridRows(support.width, support.period_us, support._row)
        assert (support.grid_native is not None) == in_c
        twin.samplers.append(support)
        twin.client.angular(60.0, -1.0)
        twin.advance(6.0)
        out.append(support.take())
    rows, python = out
    assert rows.shape == (200, 20) and np.array_equal(rows, python)
    assert rows[:, 0].tolist() == [30_000.0 * (i + 1) for i in range(200)]  # the instants first
    physics = twin.physics
    last = [
        *twin.rolling.loads,
        *physics.support.normal_forces_n(),
        physics.base_up_z(),
        *physics.base_velocity(),
    ]
    assert rows[-1, 1:].tolist() == last
    assert (
        rows[:, 13].min() < 1.0
        and np.abs(rows[:, 14:20]).max() > 0.1
        and rows[:, 7:13].max() > 50.0
    )


def test_a_mujoco_error_in_the_c_grid_is_raised_and_the_handler_restored():
    """A model whose stack overflows in mj_step: FatalError with MuJoCo's message, as the bindings
    raise it, and mju_user_error as it was."""
    xml = (
        '<mujoco><size memory="16K"/><worldbody><geom type="plane" size="5 5 .1"/>'
        + "".join(
            f'<body pos="{0.05 * i} 0 {0.1 + 0.01 * i}"><freejoint/><geom type="box" size=".1 .1 '
            f'.1"/></body>'
            for i in range(20)
        )
        + "</worldbody></mujoco>"
    )
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    handler = ctypes.c_void_p.from_address(mujoco_address("mju_user_error")).value
    stepper = grid_stepper(SimpleNamespace(model=m, data=d), ncol=0, every=10, dt_us=2000)
    assert stepper is not None and stepper.use([])
    with pytest.raises(mujoco.FatalError, match="stack overflow"):
        stepper.run(10, 20, 20_000)
    assert ctypes.c_void_p.from_address(mujoco_address("mju_user_error")).value == handler
    with pytest.raises(mujoco.FatalError, match="stack overflow"):
        mujoco.mj_step(m, d, 20)  # the bindings' own handling is untouched


def test_with_the_imu_and_lidar_the_grid_in_c_gives_the_same_messages(monkeypatch):
    """The twin with its IMU (100 Hz) and LiDAR: their samples kept in C (gs_gather of the IMU's
    sensor values and the laser site's pose), each LiDAR cast handed back to Python; the IMU,
    magnetometer and scan messages and the state are those of the Python loop, to the bit."""
    out = []
    for native in (True, False):
        monkeypatch.setattr(
            grid_loop_mod, "grid_stepper", functools.partial(grid_stepper, native=native)
        )
        calls = []
        real = grid_steps.GridStepper.run
        monkeypatch.setattr(
            grid_steps.GridStepper,
            "run",
            lambda self, *a: calls.append(real(self, *a)) or calls[-1],
        )
        twin = Twin(
            HEAVY_REAR, TwinOptions(sensors=("imu", "lidar"), visuals=False, start_xy_yaw=None)
        )
        attach_recorder(twin)
        msgs = []
        for topic, values in (
            ("imu/data_raw", lambda m: (m.angular_velocity, m.linear_acceleration)),
            ("imu/mag", lambda m: (m.magnetic_field,)),
            ("scan", lambda m: (m.ranges.tobytes(),)),
        ):
            twin.bus.subscribe(
                topic,
                lambda m, topic=topic, values=values: msgs.append(
                    (topic, m.header.stamp.to_us(), values(m))
                ),
            )
        twin.client.linear(0.5)
        twin.advance(2.0)
        twin.client.angular(-60.0, 0.0)
        twin.advance(2.0)
        out.append((msgs, twin.physics.data.qpos.copy(), calls))
    (c_msgs, c_qpos, c_calls), (py_msgs, py_qpos, py_calls) = out
    topics = [t for t, _s, _m in c_msgs]
    handoffs = sum(
        h >= 0 for _r, h in c_calls
    )  # a cast each (~22 in 4 s), not a pose sample each (200)
    assert (
        py_calls == []
        and len(c_calls) > 20
        and topics.count("scan") <= handoffs <= 2 * topics.count("scan")
    )
    assert topics.count("imu/data_raw") == 401 and topics.count("scan") >= 20
    assert c_msgs == py_msgs and np.array_equal(c_qpos, py_qpos)


def _empty_twin(monkeypatch, native: bool) -> Twin:
    """The default robot in the empty world, its grid in C (``native``) or in Python."""
    monkeypatch.setattr(
        grid_loop_mod, "grid_stepper", functools.partial(grid_stepper, native=native)
    )
    return Twin(load_config(), TwinOptions(world="empty", visuals=False))


def test_a_row_keeper_hands_back_each_due_instant_once_with_its_row(monkeypatch):
    """GridRows with work due (as the LiDAR's casts): ``after`` runs at the first kept instant at
    or after ``due_us`` (one on the grid itself), in C as in Python; every row is kept once."""
    out = []
    for native in (True, False):
        twin = _empty_twin(monkeypatch, native)
        qpos = twin.physics.data.qpos
        seen = []

        def after(t_us):
            seen.append(t_us)
            keeper.due_us = t_us + 70_000  # between two instants of the keeper

        keeper = GridRows(1, 20_000, lambda: [qpos[0]], gather([address(qpos)]), after=after)
        keeper.due_us = 60_000  # on an instant
        twin.samplers.append(keeper)
        twin.client.linear(0.5)
        twin.advance(1.0)
        out.append((seen, keeper.take()))
    (c_seen, c_rows), (py_seen, py_rows) = out
    due, expected = 60_000, []
    for t in range(20_000, 1_000_001, 20_000):
        if t >= due:
            expected.append(t)
            due = t + 70_000
    assert c_seen == py_seen == expected and expected[:3] == [60_000, 140_000, 220_000]
    assert c_rows[:, 0].tolist() == list(range(20_000, 1_000_001, 20_000)) and np.array_equal(
        c_rows, py_rows
    )
    assert c_rows[-1, 1] > 0.3  # x driven at 0.5 m/s: the values, not zeros


def test_while_a_collision_is_open_the_monitor_sees_every_instant(monkeypatch):
    """An open collision episode is extended at every grid instant (its ``until_s``, its peak
    force every 0.1 s): once the C grid hands back the instant that opens one, the rest of the
    chunk runs in Python, as every later chunk until it closes."""
    from amr_twin.sim.collisions import CollisionMonitor

    seen, open_at = set(), set()
    real_call, real_resume = CollisionMonitor.__call__, CollisionMonitor.grid_resume

    def call(self, t_us):
        seen.add(t_us)
        stop = real_call(self, t_us)
        if self._open:
            open_at.add(t_us)
        return stop

    def resume(self, t_us):
        seen.add(t_us)
        stop = real_resume(self, t_us)
        if self._open:
            open_at.add(t_us)
        return stop

    monkeypatch.setattr(CollisionMonitor, "__call__", call)
    monkeypatch.setattr(CollisionMonitor, "grid_resume", resume)
    twin = Twin(load_config(), TwinOptions(start_xy_yaw=None, visuals=False))
    twin.client.linear(0.7)
    twin.advance(8.5)  # veers into the rack's beam and scrapes along it
    hit = twin.collisions.collisions[0]
    first, last = int(round(hit.t_s * 1e6)), int(round(hit.until_s * 1e6))
    grid = set(range(first, last + 1, twin.grid_us))
    assert last - first > 200_000 and grid <= open_at and grid <= seen


@pytest.mark.parametrize("change", ["add", "remove"])
def test_samplers_added_or_removed_at_a_handed_back_instant_run_as_in_python(monkeypatch, change):
    """A row keeper's ``after`` (run at an instant the C grid handed back) adds a sampler, or
    removes one: the live list is walked at that instant, in C as in Python (the added one keeps
    its first row there)."""
    out = []
    for native in (True, False):
        twin = _empty_twin(monkeypatch, native)
        qpos = twin.physics.data.qpos
        log = []

        def keeper(period_us, after=None):
            return GridRows(1, period_us, lambda: [qpos[0]], gather([address(qpos)]), after=after)

        def first_after(t_us):
            log.append(("first", t_us))
            first.due_us = t_us + 40_000

        def second_after(t_us):
            log.append(("second", t_us))
            second.due_us = t_us + 40_000
            if t_us == 120_000:
                if change == "add":
                    twin.samplers.append(late)
                else:
                    twin.samplers.remove(last)

        first, second = keeper(20_000, first_after), keeper(20_000, second_after)
        late, last = keeper(10_000), keeper(10_000)
        first.due_us = second.due_us = 40_000
        twin.samplers += [first, second] + ([last] if change == "remove" else [])
        twin.client.linear(0.5)
        twin.advance(0.4)
        out.append((log, [k.take()[:, 0].tolist() for k in (first, second, late, last)]))
    assert out[0] == out[1]
    if change == "add":  # its first row at the instant it was added, after the one that added it
        assert out[0][1][2][0] == 120_000.0
    else:  # removed before its turn at that instant: its last row the one before
        assert out[0][1][3][-1] == 110_000.0


def test_a_row_keeper_refuses_a_period_below_one_microsecond():
    with pytest.raises(ValueError, match="period_us 0 must be >= 1"):
        GridRows(1, 0, lambda: [0.0])
    keeper = GridRows(1, 10_000, lambda: [0.0])
    with pytest.raises(ValueError, match="period_us -5 must be >= 1"):
        keeper.period_us = -5
    assert keeper.period_us == 10_000


def test_with_actors_the_grid_in_c_gives_the_python_loops_bits(monkeypatch):
    """People and a pallet jack moved by actors.c on the C grid and by their Python twin on the
    Python grid: a person waiting for the robot, one walking into it (a collision, the Python loop
    while it lasts), a looping jack; the LiDAR casting every 20 ms. The state, the mocap poses, the
    published poses and scans and the episodes are the same to the bit; the C grid ran."""
    import amr_twin.sim.actors as actors_mod
    from amr_twin.model.actors import Actor

    actors = (
        Actor("person", ((-2.5, 0.3), (-8.0, 0.3)), 1.3, stop_within_m=1.0),
        Actor("person", ((-4.8, -2.0), (-4.8, 2.0)), 0.9, start_s=1.0),
        Actor("pallet_jack", ((0.0, 1.5), (4.0, 1.5), (4.0, -1.5)), 1.2, loop=True),
    )
    out = []
    real_open = actors_mod.open_helper
    for native in (True, False):
        monkeypatch.setattr(
            actors_mod, "open_helper", lambda src, nat=True, native=native: real_open(src, native)
        )
        monkeypatch.setattr(
            grid_loop_mod, "grid_stepper", functools.partial(grid_stepper, native=native)
        )
        calls = []
        real = grid_steps.GridStepper.run
        monkeypatch.setattr(
            grid_steps.GridStepper,
            "run",
            lambda self, *a: calls.append(real(self, *a)) or calls[-1],
        )
        twin = Twin(
            load_config(),
            TwinOptions(sensors=("imu", "lidar"), visuals=False, start_xy_yaw=None, actors=actors),
        )
        attach_recorder(twin)
        assert twin.actors.engine == ("C" if native else "Python (native=False)")
        msgs = []
        twin.bus.subscribe(
            "actors/poses",
            lambda m: msgs.append(
                [(p.position.x, p.position.y, p.orientation.z, p.orientation.w) for p in m.poses]
            ),
            queue_size=100,
        )
        twin.bus.subscribe("scan", lambda m: msgs.append(m.ranges.tobytes()), queue_size=100)
        twin.client.linear(0.3)
        twin.advance(4.0)
        d = twin.physics.data
        out.append(
            (
                msgs,
                d.qpos.copy(),
                d.mocap_pos.copy(),
                d.mocap_quat.copy(),
                twin.collisions.as_dicts(),
                twin.actors.progress_s(),
                calls,
            )
        )
    c, py = out
    assert py[-1] == [] and len(c[-1]) > 20
    assert (
        "person_1" in [h["hit"] for h in c[4]] and c[5][0] < 3.0
    )  # one walked into it, one waited
    assert c[0] == py[0] and len(c[0]) > 60
    for a, b in zip(c[1:6], py[1:6]):
        assert np.array_equal(np.asarray(a), np.asarray(b)) if not isinstance(a, list) else a == b
