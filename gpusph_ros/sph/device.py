"""Which Warp device a run uses unless it names one, and what ``device: auto`` picks."""
import os

AUTO = "auto"  # the run setting device: the first CUDA device Warp sees, else the CPU


def default_device() -> str:
    """$GPUSPH_ROS_DEVICE (cuda:0, say), else cpu."""
    return os.environ.get("GPUSPH_ROS_DEVICE", "cpu")


def chosen_device(device: str) -> str:
    """The Warp device a run of ``device`` steps on: itself, or for ``auto`` the first CUDA device
    Warp sees on this machine, else cpu. Taken where a model is built: a study or plan may name
    ``auto`` for another machine."""
    if device != AUTO:
        return device
    import warp as wp

    cuda = [d.alias for d in wp.get_devices() if d.is_cuda]
    return cuda[0] if cuda else "cpu"


def choice(device: str, chosen: str) -> str:
    """What a run says of its device: "" where it was named, else why ``auto`` chose it."""
    if device != AUTO:
        return ""
    return f"device auto: {chosen}, " + ("the first CUDA device Warp sees" if chosen != "cpu"
                                         else "Warp sees no CUDA device")
