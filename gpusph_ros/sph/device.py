"""Which Warp device a run uses unless it names one."""
import os


def default_device() -> str:
    """$GPUSPH_ROS_DEVICE (cuda:0, say), else cpu."""
    return os.environ.get("GPUSPH_ROS_DEVICE", "cpu")
