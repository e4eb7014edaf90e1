"""Starts the linkspace node with robot_description from a xacro file.

    ros2 launch linkspace_bringup linkspace.launch.py
    ros2 launch linkspace_bringup linkspace.launch.py model:=/path/robot.urdf.xacro \
        xacro_args:='crank:=1.6' params_file:=/path/params.yaml namespace:=/lab \
        network:=all publish_state:=true

The node (`lib/linkspace_bringup/linkspace serve`) gets the parameters file first and then
robot_description, the output of `xacro MODEL XACRO_ARGS`, which launch_ros writes to a
parameters file of its own. With publish_state:=true, robot_state_publisher runs beside it with
the same description (TF of the fixed joints, and /robot_description for RViz).

The names below the imports of generate_launch_description are plain Python, so a test can build
the same command line and parameters without a ROS install.
"""

import shlex

PACKAGE = 'linkspace_bringup'
EXECUTABLE = 'linkspace'
NODE_NAME = 'linkspace'
#: Launch arguments and their defaults; paths are relative to the package's share folder.
DEFAULTS = {
    'model': 'urdf/four_bar.urdf.xacro',
    'xacro_args': '',
    'params_file': 'config/linkspace.yaml',
    'namespace': '/',
    'network': 'loopback',
    'publish_state': 'false',
}


def serve_arguments(network):
    """The node's own arguments; launch_ros appends --ros-args with the name, the namespace and
    one --params-file per entry of parameters."""
    return ['serve', '--network', network]


def xacro_command(model, xacro_args):
    """The command whose output is robot_description (launch's Command splits it with shlex)."""
    return ['xacro', model] + shlex.split(xacro_args)


def generate_launch_description():
    from launch import LaunchDescription
    from launch.actions import DeclareLaunchArgument
    from launch.conditions import IfCondition
    from launch.substitutions import Command, LaunchConfiguration, PathJoinSubstitution
    from launch_ros.actions import Node
    from launch_ros.parameter_descriptions import ParameterValue
    from launch_ros.substitutions import FindPackageShare

    share = FindPackageShare(PACKAGE)
    arg = LaunchConfiguration
    declared = []
    for name, default in DEFAULTS.items():
        if '/' in default and not default.startswith('/'):
            default = PathJoinSubstitution([share, default])
        declared.append(DeclareLaunchArgument(name, default_value=default))
    robot_description = ParameterValue(
        Command(['xacro ', arg('model'), ' ', arg('xacro_args')]), value_type=str)
    linkspace = Node(
        package=PACKAGE,
        executable=EXECUTABLE,
        name=NODE_NAME,
        namespace=arg('namespace'),
        arguments=serve_arguments(arg('network')),
        parameters=[arg('params_file'), {'robot_description': robot_description}],
        output='screen',
    )
    state_publisher = Node(
        package='robot_state_publisher',
        executable='robot_state_publisher',
        namespace=arg('namespace'),
        parameters=[{'robot_description': robot_description}],
        condition=IfCondition(arg('publish_state')),
        output='screen',
    )
    return LaunchDescription(declared + [linkspace, state_publisher])
