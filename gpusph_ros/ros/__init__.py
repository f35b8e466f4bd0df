"""The ROS 2 node over the runner: sim_node, its parameters (node_params) and its solver thread (session)."""
