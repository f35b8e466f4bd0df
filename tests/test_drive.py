"""What a driven body does with its commands (gpusph_ros/drive.py), without a solver: refusals,
clamps, and the segments a pose jump, a twist and silence give, integrated here as the solver's
driven_pose integrates them (constant accelerations from the segment's start)."""
import math

import numpy as np
import pytest

from gpusph_ros.drive import BodyDriver, rotation_vector
from gpusph_ros.sph.bodies import Motion

pytestmark = pytest.mark.unit
DT = 0.05  # the output interval


def paddle(**limits) -> BodyDriver:
    """A 2D paddle 6 cm thick and 0.6 m tall whose centre starts at (0.07, 0.3) in a 1 m tank."""
    motion = Motion(law="driven", centre=(0.07, 0.3, 0.0), **{"max_speed": 0.5, "max_acceleration": 5.0,
                                                               "max_angular_speed": 1.0,
                                                               "max_angular_acceleration": 10.0,
                                                               "timeout": 0.5, **limits})
    return BodyDriver(motion, 2, (0.04, 0.0, 0.0), (0.1, 0.6, 0.0), (1.0, 0.6, 0.0))


def run(driver, pose, start, end):
    """Step ``pose`` (a dict as Solver.body_poses gives) through the driver's segments from start to
    end; the positions and velocities at each output."""
    out = []
    t = start
    while t < end - 1e-12:
        s = driver.segment(t, DT, pose)
        x = s["position"] + s["velocity"] * DT + s["acceleration"] * DT * DT / 2
        v = s["velocity"] + s["acceleration"] * DT
        w = s["omega"] + s["angular_acceleration"] * DT
        angle = (s["omega"] + s["angular_acceleration"] * DT / 2) * DT  # about z in 2D
        q = np.asarray(pose["quaternion"])
        turn = np.array([0.0, 0.0, math.sin(angle[2] / 2), math.cos(angle[2] / 2)])
        q = np.array([turn[3] * q[0] + turn[0] * q[3] + turn[1] * q[2] - turn[2] * q[1],
                      turn[3] * q[1] - turn[0] * q[2] + turn[1] * q[3] + turn[2] * q[0],
                      turn[3] * q[2] + turn[0] * q[1] - turn[1] * q[0] + turn[2] * q[3],
                      turn[3] * q[3] - turn[0] * q[0] - turn[1] * q[1] - turn[2] * q[2]])
        pose = {"position": x, "velocity": v, "omega": w, "quaternion": q}
        t += DT
        out.append((t, x.copy(), v.copy(), w.copy(), q.copy()))
    return out, pose


def at_rest():
    return {"position": np.array([0.07, 0.3, 0.0]), "velocity": np.zeros(3), "omega": np.zeros(3),
            "quaternion": np.array([0.0, 0.0, 0.0, 1.0])}


@pytest.mark.parametrize("kind, stamp, a, b, why", [
    ("pose", 1.0, [math.nan, 0.3, 0.0], [0, 0, 0, 1], "not finite"),
    ("pose", 1.2, [0.1, 0.3, 0.0], [0, 0, 0, 1], "later than the simulated time"),
    ("pose", 0.4, [0.1, 0.3, 0.0], [0, 0, 0, 1], "older than the timeout"),
    ("pose", 1.0, [0.1, 0.3, 0.0], [0, 0, 0, 2], "norm is 2"),
    ("spin", 1.0, [0.1, 0.3, 0.0], [0, 0, 0, 1], "not one of pose, twist"),
])
def test_a_bad_command_is_refused_with_its_reason(kind, stamp, a, b, why):
    driver = paddle()
    taken, reason = driver.command(kind, stamp, 1.0, a, b)
    assert not taken and why in reason
    assert driver.segment(1.0, DT, at_rest())["acceleration"] == pytest.approx([0.0, 0.0, 0.0])  # nothing held


def test_a_command_older_than_the_last_one_is_refused():
    driver = paddle()
    assert driver.command("pose", 0.9, 1.0, [0.1, 0.3, 0.0], [0, 0, 0, 1])[0]
    taken, reason = driver.command("pose", 0.8, 1.0, [0.2, 0.3, 0.0], [0, 0, 0, 1])
    assert not taken and "before the last command" in reason


def test_a_pose_jump_is_walked_at_the_limits_and_lands_without_overshoot():
    """A jump of 0.5 m (the command held 10 s): the speed never passes 0.5 m/s nor changes by more
    than 5 m/s^2 x dt a step, the paddle arrives (within 1 mm by 2 s) and never passes the target by
    more than 2 mm."""
    driver = paddle(timeout=10.0)
    assert driver.command("pose", 0.0, 0.0, [0.57, 0.3, 0.0], [0, 0, 0, 1]) == (True, "taken")
    rows, _ = run(driver, at_rest(), 0.0, 2.0)
    x = np.array([r[1][0] for r in rows])
    v = np.array([r[2][0] for r in rows])
    assert np.abs(v).max() <= 0.5 + 1e-12 and np.abs(np.diff(np.concatenate([[0.0], v]))).max() <= 5.0 * DT + 1e-12
    assert x[-1] == pytest.approx(0.57, abs=1e-3) and x.max() <= 0.57 + 0.002


def test_a_pose_beyond_the_tank_stops_at_its_wall_and_a_2d_body_turns_about_z_only():
    driver = paddle(timeout=10.0)
    turn = np.array([0.3, 0.0, math.sin(0.1), math.cos(0.1)])  # a tilt about x the 2D body cannot take
    assert driver.command("pose", 0.0, 0.0, [5.0, 0.3, 0.0], turn / np.linalg.norm(turn))[0]
    rows, pose = run(driver, at_rest(), 0.0, 4.0)
    assert pose["position"][0] == pytest.approx(1.0 - 0.03, abs=1e-3)  # its box against the far wall
    assert pose["omega"][:2] == pytest.approx([0.0, 0.0]) and abs(pose["quaternion"][2]) > 0.05


def test_a_twist_is_clamped_and_silence_brings_the_body_to_rest():
    driver = paddle()
    taken, note = driver.command("twist", 0.0, 0.0, [2.0, 0.0, 0.0], [0.0, 0.0, 0.0])
    assert taken and "clamped to max_speed 0.5" in note
    rows, pose = run(driver, at_rest(), 0.0, 0.5)
    assert rows[-1][2][0] == pytest.approx(0.5)  # at the limit, reached at 5 m/s^2
    rows, pose = run(driver, pose, 0.5, 1.0)  # the command is now older than the 0.5 s timeout
    assert rows[-1][2] == pytest.approx([0.0, 0.0, 0.0])


def test_a_twist_too_large_for_its_norm_is_clamped_along_its_direction():
    # 1e154 m/s on two axes overflowed the norm to inf and became no velocity, "clamped" all the same
    driver = paddle()
    taken, note = driver.command("twist", 0.0, 0.0, [1e154, 1e154, 0.0], [0.0, 0.0, 0.0])
    assert taken and "clamped to max_speed 0.5" in note
    accel = driver.segment(0.0, DT, at_rest())["acceleration"]
    assert accel[0] == pytest.approx(accel[1]) and accel[0] > 0.0 and accel[2] == 0.0


def test_the_rotation_vector_is_the_shorter_way():
    q = np.array([0.0, 0.0, math.sin(-0.3), math.cos(-0.3)])
    assert rotation_vector(q, np.array([0.0, 0.0, 0.0, 1.0])) == pytest.approx([0.0, 0.0, -0.6])
    assert rotation_vector(-q, np.array([0.0, 0.0, 0.0, 1.0])) == pytest.approx([0.0, 0.0, -0.6])
