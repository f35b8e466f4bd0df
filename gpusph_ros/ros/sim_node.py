"""sim_node: the solver live in ROS 2.

For now this entry point reports the package and solver versions; the node itself (parameters,
services, topics, recording) is its own piece of work.
"""
import sys

from .. import __version__


def main(argv=None):
    import warp

    print(f"gpusph_ros sim_node {__version__} (warp {warp.config.version})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
