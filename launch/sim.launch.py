"""sim_node with a scene, a spacing, a parameter file, a recording folder and, optionally, RViz.

    ros2 launch gpusph_ros sim.launch.py scene:=dambreak1_lab dx:=0.03 rviz:=true
    ros2 launch gpusph_ros sim.launch.py params_file:=/path/to/my.yaml record_dir:=~/bags

``params_file`` (default: the package's config/sim_node.yaml, every parameter at its default) is
read first; ``scene``, ``dx`` and ``record_dir`` given here win over it. RViz opens the package's
rviz/sim.rviz: the cloud coloured by pressure, the scene's geometry, each body's force arrow.
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.conditions import IfCondition
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node
from launch_ros.parameter_descriptions import ParameterValue

SHARE = get_package_share_directory("gpusph_ros")


def generate_launch_description():
    arguments = [
        DeclareLaunchArgument("scene", default_value="dambreak1_thesis",
                              description="a built-in scene (config/scenes) or a scene YAML file"),
        DeclareLaunchArgument("dx", default_value="0.03", description="particle spacing [m]"),
        DeclareLaunchArgument("params_file", default_value=os.path.join(SHARE, "config", "sim_node.yaml"),
                              description="a sim_node parameter file, read before the arguments above"),
        DeclareLaunchArgument("record_dir", default_value="",
                              description="folder for MCAP recordings (one sub-folder each); empty: none"),
        DeclareLaunchArgument("rviz", default_value="false", description="open RViz with rviz/sim.rviz"),
    ]
    sim = Node(
        package="gpusph_ros",
        executable="sim_node",
        name="sim_node",
        output="screen",
        parameters=[LaunchConfiguration("params_file"),
                    # typed: dx:=1 is a float, not an int the node refuses; a scene named 1 is a string
                    {"scene": ParameterValue(LaunchConfiguration("scene"), value_type=str),
                     "dx": ParameterValue(LaunchConfiguration("dx"), value_type=float),
                     "record_dir": ParameterValue(LaunchConfiguration("record_dir"), value_type=str)}],
    )
    rviz = Node(
        package="rviz2",
        executable="rviz2",
        name="rviz2",
        arguments=["-d", os.path.join(SHARE, "rviz", "sim.rviz")],
        condition=IfCondition(LaunchConfiguration("rviz")),
    )
    return LaunchDescription([*arguments, sim, rviz])
