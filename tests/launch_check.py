"""What `ros2 launch linkspace_bringup linkspace.launch.py` starts, built without ROS's launch
tools (launch, launch_ros and ros2launch have no PyPI wheels): the package is found in the
ament index (AMENT_PREFIX_PATH) as FindPackageShare and Node(package=...) find it, the installed
launch file's own functions and defaults give the xacro command and the node's arguments, and
the node's parameters are
written as launch_ros 0.26 (Jazzy) writes them: the parameters file as given, then
`parameters=[{'robot_description': ...}]` as `Node._create_params_file_from_dict` dumps it,
`yaml.dump({NODE: {'ros__parameters': params}}, default_flow_style=False)` under the node's
fully qualified name, each passed with `--params-file` after `--ros-args -r __node:= -r __ns:=`.

Prints one JSON line: {"argv": the node's command line, "params_files": [...],
"robot_description": the xacro output}.
"""

import argparse
import importlib.util
import json
import os
import shutil
import subprocess
import sys
import tempfile

from ament_index_python.packages import get_package_prefix, get_package_share_directory
import yaml


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--package", default="linkspace_bringup")
    ap.add_argument("--namespace", default=None)
    ap.add_argument("--xacro-args", default=None)
    args = ap.parse_args()

    share = get_package_share_directory(args.package)
    spec = importlib.util.spec_from_file_location(
        "linkspace_launch", os.path.join(share, "launch", "linkspace.launch.py"))
    launch_file = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(launch_file)
    defaults = dict(launch_file.DEFAULTS)
    namespace = args.namespace if args.namespace is not None else defaults["namespace"]
    xacro_args = args.xacro_args if args.xacro_args is not None else defaults["xacro_args"]
    model = os.path.join(share, defaults["model"])
    params_file = os.path.join(share, defaults["params_file"])
    # launch_ros's ExecutableInPackage: PREFIX/lib/PACKAGE/EXECUTABLE.
    prefix = get_package_prefix(launch_file.PACKAGE)
    executable = os.path.join(prefix, "lib", launch_file.PACKAGE, launch_file.EXECUTABLE)

    # launch's Command runs the command from PATH; the venv's xacro sits beside its python.
    cmd = launch_file.xacro_command(model, xacro_args)
    found = shutil.which(cmd[0], path=os.path.dirname(sys.executable) + os.pathsep + os.environ.get("PATH", ""))
    if found is None:
        sys.exit("launch_check.py: no xacro on PATH or beside this python (scripts/ros_env.sh installs it)")
    cmd[0] = found
    description = subprocess.run(cmd, check=True, capture_output=True, text=True).stdout

    if not namespace.startswith("/"):
        namespace = "/" + namespace
    node = ("" if namespace == "/" else namespace.rstrip("/")) + "/" + launch_file.NODE_NAME
    with tempfile.NamedTemporaryFile(mode="w", prefix="launch_params_", suffix=".yaml", delete=False) as h:
        yaml.dump({node: {"ros__parameters": {"robot_description": description}}}, h, default_flow_style=False)
    files = [params_file, h.name]
    argv = [executable] + launch_file.serve_arguments(defaults["network"])
    argv += ["--ros-args", "-r", "__node:=" + launch_file.NODE_NAME, "-r", "__ns:=" + namespace]
    for f in files:
        argv += ["--params-file", f]
    print(json.dumps({"argv": argv, "params_files": files, "robot_description": description}))


if __name__ == "__main__":
    main()
