"""gpusph_ros: a weakly-compressible SPH free-surface solver on NVIDIA Warp, live in ROS 2."""

__version__ = "0.1.0"
