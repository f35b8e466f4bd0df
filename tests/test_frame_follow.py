"""Driven bodies that follow a TF frame (ros/frame_follow.py; issue 45, item 4): the frame's pose in
the world frame composed from /tf's links, and a body in a run following it as it would a cmd_pose.
tf2_msgs has no wheel: the transforms are stand-ins with geometry_msgs' fields."""
import math
from types import SimpleNamespace

import numpy as np
import pytest

from gpusph_ros.ros.frame_follow import FrameFollower, command, frame_in
from gpusph_ros.scenes.schema import parse_scene
from gpusph_ros.sph.config import ConfigError


def transform(parent: str, child: str, xyz=(0.0, 0.0, 0.0), yaw: float = 0.0, stamp: float = 0.0, quat=None):
    """A TransformStamped stand-in: ``child`` in ``parent`` at ``xyz``, turned by ``yaw`` about z."""
    x, y, z, w = quat if quat is not None else (0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2))
    sec = int(stamp)
    stamp = SimpleNamespace(sec=sec, nanosec=int(round((stamp - sec) * 1e9)))
    return SimpleNamespace(
        header=SimpleNamespace(frame_id=parent, stamp=stamp),
        child_frame_id=child,
        transform=SimpleNamespace(translation=SimpleNamespace(x=xyz[0], y=xyz[1], z=xyz[2]),
                                  rotation=SimpleNamespace(x=x, y=y, z=z, w=w)))


@pytest.mark.unit
def test_a_chain_of_frames_composes_to_the_world():
    """world -> base (1, 0, 0), turned 90 degrees about z -> arm (0.5, 0, 0.2) in base: the arm
    stands at (1, 0.5, 0.2), turned 90 degrees; the stamp is the moving link's."""
    follower = FrameFollower({"paddle": "arm"}, "world")
    assert follower.take([transform("world", "base", (1.0, 0.0, 0.0), math.pi / 2)], static=True) == []
    ((body, (position, rotation, stamp)),) = follower.take([transform("base", "arm", (0.5, 0.0, 0.2), stamp=2.5)])
    assert body == "paddle" and stamp == pytest.approx(2.5)
    np.testing.assert_allclose(position, [1.0, 0.5, 0.2], atol=1e-12)
    np.testing.assert_allclose(rotation, [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], atol=1e-12)


@pytest.mark.unit
def test_what_cannot_be_composed_is_said_and_not_taken():
    follower = FrameFollower({"paddle": "arm"}, "world")
    ((_, why),) = follower.take([transform("base", "arm", (0.5, 0.0, 0.0))])
    assert "no transform yet connects 'arm' to 'world'" in why and "'base'" in why
    ((_, why),) = follower.take([transform("arm", "base")])
    assert "loop" in why
    follower = FrameFollower({"paddle": "arm"}, "world")
    ((_, why),) = follower.take([transform("world", "arm", quat=(0.0, 0.0, 0.0, 2.0))])
    assert "unit rotation" in why and "arm" not in follower.links
    ((_, why),) = follower.take([transform("world", "arm", (math.nan, 0.0, 0.0))])
    assert "not finite" in why
    # the node's own body frames, which it publishes on /tf, are never links
    assert follower.take([transform("world", "world/paddle", (9.0, 0.0, 0.0))]) == []
    assert "world/paddle" not in follower.links
    # a static chain has no stamp: the command is now
    ((_, (position, _, stamp)),) = follower.take([transform("world", "arm", (0.1, 0.0, 0.0))], static=True)
    assert stamp is None and position[0] == pytest.approx(0.1)
    assert frame_in(follower.links, "elsewhere", "world").startswith("no transform yet")


@pytest.mark.unit
@pytest.mark.parametrize("frame, allowed", [("2arm", "a TF frame id"), ("a//b", "a TF frame id"),
                                            ("x" * 300, "at most 256"), (3, "a TF frame id")])
def test_a_bad_frame_is_refused_naming_its_field(frame, allowed):
    with pytest.raises(ConfigError) as err:
        parse_scene(paddle_tank(frame))
    assert err.value.field == "obstacles[0].motion.frame" and allowed in str(err.value)


def paddle_tank(frame) -> dict:
    """A 2D tank 1.2 m long, 0.3 m of water, a paddle 4 cm thick at x = 0.1 m driven by ``frame``."""
    return {"name": "followed", "dim": 2, "tank": [1.2, 0.5], "walls": "particles",
            "fluid": [{"name": "water", "lo": [0.14, 0.0], "hi": [1.2, 0.3]}],
            "obstacles": [{"name": "paddle", "lo": [0.1, 0.0], "hi": [0.14, 0.5],
                           "motion": {"type": "driven", "max_speed": 0.5, "max_acceleration": 5.0,
                                      "frame": frame}}]}


@pytest.mark.physics
def test_a_body_follows_its_frame_as_a_robot_moves_it():
    """The paddle's frame, ``robot/paddle``, on a 1 Hz, 2 cm sinusoid along x under a static
    ``robot`` frame 0.12 m along the world's x, a transform at each output (0.05 s of simulated
    time), stamped then: at the next output the paddle stands within 4 mm of where the frame was
    (the driver walks to the newest pose within its limits), and
    the fluid's force comes back each output, over the period the hydrostatic load rho g h^2 / 2 =
    441 N/m on the paddle within 10%."""
    from gpusph_ros.runner import Run
    from gpusph_ros.scenes.settings import resolve

    scene = parse_scene(paddle_tank("robot/paddle"))
    run = Run(scene, resolve(scene, sets=["dx=0.02", "end_time=1.0", "output_rate=20"]))
    follower = FrameFollower({"paddle": "robot/paddle"}, run.frame_id)
    follower.take([transform(run.frame_id, "robot", (0.12, 0.0, 0.0))], static=True)

    def frame_x(t):
        return 0.02 * math.sin(2 * math.pi * t)

    run.step_output()
    gaps, forces = [], []
    while not run.done:
        t0 = run.solver.time
        ((_, result),) = follower.take([transform("robot", "robot/paddle", (frame_x(t0), 0.0, 0.0), stamp=t0)])
        assert command(run, "paddle", result) == (True, "taken")
        msgs = run.step_output()
        gaps.append(abs(run.solver.body_poses()[0]["position"][0] - (0.12 + frame_x(t0))))
        forces += [m for topic, m in msgs if topic.endswith("/bodies/paddle/wrench")]
    assert max(gaps) < 0.004 and len(forces) == len(gaps) == run.n_outputs - 1
    assert np.mean([f.wrench.force.x for f in forces]) == pytest.approx(-1000.0 * 9.81 * 0.3 ** 2 / 2, rel=0.1)
    assert run.solver.excluded_particles == 0


@pytest.mark.unit
def test_what_tf_carries_is_bounded():
    """Empty and over-long frame ids are not kept; the links stop at MAX_LINKS, the least recently
    set off the followed chain going first (200,000 frames held 92 MiB); a chain deeper than
    MAX_CHAIN is refused with the reason (10,000 links cost 110 ms a message) - issue 58."""
    from gpusph_ros.ros import frame_follow

    follower = FrameFollower({"paddle": "arm"}, "world")
    assert follower.take([transform("world", ""), transform("world", "x" * 100_000), transform("", "a")]) == []
    assert follower.links == {}
    follower.take([transform("world", "base"), transform("base", "arm", (0.5, 0.0, 0.0))])
    follower.take([transform("world", f"junk_{k}") for k in range(frame_follow.MAX_LINKS + 10)])
    assert len(follower.links) == frame_follow.MAX_LINKS
    assert {"base", "arm", f"junk_{frame_follow.MAX_LINKS + 9}"} <= set(follower.links)
    assert "junk_0" not in follower.links
    deep = FrameFollower({"paddle": "f0"}, "world")
    links = [transform(f"f{k + 1}", f"f{k}") for k in range(frame_follow.MAX_CHAIN + 5)]
    ((_, why),) = deep.take(links + [transform("world", f"f{frame_follow.MAX_CHAIN + 5}")])
    assert f"more than {frame_follow.MAX_CHAIN} links deep" in why
