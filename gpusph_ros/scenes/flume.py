"""A 2D wave flume: a paddle at the left end making regular waves (a ``piston`` or ``flap`` motion,
scenes/schema.py) in still water, and free-surface gauges down it (bench/wavemaker.py)."""
from .schema import parse_scene

PADDLE = (0.04, 0.1)  # [m] the paddle's back and face along the flume


def wave_flume(length: float, depth: float, period: float, wave_height: float, gauges, kind: str = "piston",
               ramp: float | None = None, walls: str = "particles", first: int = 1):
    """The scene: a flume ``length`` long with ``depth`` of water, ``walls`` twice the depth high,
    the paddle's face at PADDLE[1] and gauges ``g<first>``, ``g<first + 1>``, ... ``gauges`` [m] from
    it; the paddle's amplitude ramped in over ``ramp`` (default the motion's, two periods)."""
    motion = {"type": kind, "wave_height": wave_height, "period": period}
    if ramp is not None:
        motion["ramp"] = ramp
    face = PADDLE[1]
    return parse_scene({
        "name": "flume", "dim": 2, "tank": [length, 2 * depth], "depth": depth, "walls": walls,
        "fluid": [{"name": "water", "lo": [face, 0.0], "hi": [length, depth]}],
        "obstacles": [{"name": "paddle", "lo": [PADDLE[0], 0.0], "hi": [face, 2 * depth], "motion": motion}],
        "probes": {f"g{n + first}": {"type": "gauge", "position": [float(face + x)]} for n, x in enumerate(gauges)}})
