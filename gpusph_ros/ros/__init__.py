"""The thin ROS 2 shell over the solver: node, message conversion, recording."""
