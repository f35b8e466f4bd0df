"""sim_node stepped in lockstep with gz-sim (NOT RUN HERE: these machines have no gz-sim; written
for ROS 2 Jazzy with ros_gz_sim, ros_gz_bridge and ros_gz_interfaces from apt, gz-sim Harmonic).

    ros2 launch gpusph_ros gz_lockstep.launch.py world:=/path/to/world.sdf world_name:=default \\
        scene:=paddle_2d dx:=0.04 body:=paddle

gz-sim starts paused (no -r) with ``world``; ros_gz_bridge carries its /clock, the robot's poses and
the fluid's wrench (config/gz_bridge.yaml) and its world control service; sim_node runs with
``clock: lockstep`` and ``wrench_rate`` at the loop's rate; examples/lockstep_loop.py steps gz-sim by
``step`` through the control service, waits for its /clock, then advances the fluid to the same time
and reads the body's wrench. Nothing here is in package.xml: gz-sim is an optional companion.
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, ExecuteProcess, IncludeLaunchDescription, OpaqueFunction
from launch.launch_description_sources import PythonLaunchDescriptionSource
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

SHARE = get_package_share_directory("gpusph_ros")


def _nodes(context):
    value = {name: LaunchConfiguration(name).perform(context) for name in
             ("world", "world_name", "scene", "dx", "body", "step", "end")}
    rate = 1.0 / float(value["step"])
    gz = IncludeLaunchDescription(
        PythonLaunchDescriptionSource(os.path.join(get_package_share_directory("ros_gz_sim"), "launch",
                                                   "gz_sim.launch.py")),
        launch_arguments={"gz_args": value["world"]}.items())  # no -r: paused, stepped by the loop
    bridge = Node(package="ros_gz_bridge", executable="parameter_bridge", name="gz_bridge", output="screen",
                  arguments=[f"/world/{value['world_name']}/control@ros_gz_interfaces/srv/ControlWorld"],
                  parameters=[{"config_file": os.path.join(SHARE, "config", "gz_bridge.yaml")}])
    sim = Node(package="gpusph_ros", executable="sim_node", name="sim_node", output="screen",
               parameters=[{"scene": value["scene"], "dx": float(value["dx"]), "clock": "lockstep",
                            "wrench_rate": rate}])
    loop = ExecuteProcess(cmd=["python3", os.path.join(SHARE, "examples", "lockstep_loop.py"), "--body",
                               value["body"], "--step", value["step"], "--end", value["end"], "--gz-world",
                               value["world_name"], "--gz-step", value["step"]], output="screen")
    return [gz, bridge, sim, loop]


def generate_launch_description():
    return LaunchDescription([
        DeclareLaunchArgument("world", default_value="empty.sdf", description="gz-sim's world (an SDF file)"),
        DeclareLaunchArgument("world_name", default_value="default", description="the world's name in the SDF"),
        DeclareLaunchArgument("scene", default_value="paddle_2d", description="sim_node's scene"),
        DeclareLaunchArgument("dx", default_value="0.04", description="particle spacing [m]"),
        DeclareLaunchArgument("body", default_value="paddle", description="the body whose wrench the loop reads"),
        DeclareLaunchArgument("step", default_value="0.001", description="[s] each lockstep advance (gz's step)"),
        DeclareLaunchArgument("end", default_value="10.0", description="[s] simulated, the loop's last target"),
        OpaqueFunction(function=_nodes),
    ])
