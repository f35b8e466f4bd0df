"""What a run sends out, under the runner: ROS 2 messages built from the measurements (messages),
their definitions for MCAP schemas (msgdefs), the rosbag2 MCAP recorder (recording) and the saved
state's file, data that cannot run code (state_file). Uses
rclpy's message classes and serialisation, no node; ros/ holds the node, above the runner."""
