#!/bin/sh
# Makes (once) the Python environment that talks ROS 2 Jazzy to the linkspace node: real rclpy
# with Fast DDS from pinned PyPI wheels, plus linkspace_msgs (msgs/) and tf2_msgs' TFMessage
# (ros/tf2_msgs/) built with rosidl into it.
# Nothing else is needed on the machine but CPython 3.11, a C/C++ compiler and PyPI.
#
# Usage: scripts/ros_env.sh [VENV]      (default: target/ros-venv)
# Prints the venv's python on the last line. Idempotent: a stamp records the hash of the inputs
# (this script, the requirements and the interface packages), so a second call returns at once,
# and a change to msgs/ rebuilds only the interfaces. Concurrent callers wait on a lock.
set -eu
ROOT=$(cd "$(dirname "$0")/.." && pwd)
VENV=${1:-$ROOT/target/ros-venv}
mkdir -p "$(dirname "$VENV")"
VENV=$(cd "$(dirname "$VENV")" && pwd)/$(basename "$VENV")
PY=${LINKSPACE_PYTHON:-python3}

exec 9>"$VENV.lock"
flock 9

hash_of() { cat "$@" | sha256sum | cut -d' ' -f1; }
# The venv and its build trees hold copies of interface packages: a colcon workspace around
# this clone must not find them (colcon skips a folder holding COLCON_IGNORE), even while
# they are being made.
hide_from_colcon() {
  mkdir -p "$VENV" "$VENV.msgs-build"
  touch "$VENV/COLCON_IGNORE" "$VENV.msgs-build/COLCON_IGNORE"
}
REQ_HASH=$(hash_of "$ROOT/scripts/ros-requirements.txt")
# The interface packages built here: linkspace_msgs, and tf2_msgs' TFMessage (no wheel on PyPI).
MSG_HASH=$(cd "$ROOT" && find msgs ros/tf2_msgs -type f | LC_ALL=C sort | xargs cat | sha256sum | cut -d' ' -f1)
SCRIPT_HASH=$(hash_of "$ROOT/scripts/ros_env.sh")

if [ "$(cat "$VENV/.linkspace-req" 2>/dev/null)" != "$REQ_HASH $SCRIPT_HASH" ]; then
  case "$($PY -c 'import sys; print("%d.%d" % sys.version_info[:2])')" in
    3.11) ;;
    *) echo "ros_env.sh: the ros-jazzy wheels need CPython 3.11; set LINKSPACE_PYTHON" >&2; exit 1 ;;
  esac
  rm -rf "$VENV"
  "$PY" -m venv "$VENV"
  hide_from_colcon
  "$VENV/bin/pip" install -q --disable-pip-version-check -r "$ROOT/scripts/ros-requirements.txt" >&2
  # The wheels were built in a manylinux image; their exported CMake targets name that image's
  # Python paths. Point them at this interpreter's, or rosidl's Python generator fails.
  PYINC=$("$VENV/bin/python" -c "import sysconfig; print(sysconfig.get_paths()['include'])")
  PYSITE=$("$VENV/bin/python" -c "import sysconfig; print(sysconfig.get_paths()['purelib'])")
  grep -rl "/opt/python/cp3" "$VENV/share" --include='*.cmake' 2>/dev/null | xargs -r sed -i \
    -e "s#/opt/python/cp3[0-9]*-cp3[0-9]*/lib/python3\.[0-9]*/site-packages#$PYSITE#g" \
    -e "s#/opt/python/cp3[0-9]*-cp3[0-9]*/include/python3\.[0-9]*#$PYINC#g"
  echo "$REQ_HASH $SCRIPT_HASH" > "$VENV/.linkspace-req"
  rm -f "$VENV/.linkspace-msgs"
fi

if [ "$(cat "$VENV/.linkspace-msgs" 2>/dev/null)" != "$MSG_HASH" ]; then
  : > "$VENV.msgs-build.log"
  for PKG in ros/tf2_msgs msgs; do
    BUILD="$VENV.msgs-build/$(basename "$PKG")"
    rm -rf "$BUILD"
    if ! { PATH="$VENV/bin:$PATH" cmake -S "$ROOT/$PKG" -B "$BUILD" -DCMAKE_PREFIX_PATH="$VENV" \
        -DCMAKE_INSTALL_PREFIX="$VENV" -DPython3_EXECUTABLE="$VENV/bin/python" -DBUILD_TESTING=OFF \
        -DCMAKE_BUILD_TYPE=Release &&
      PATH="$VENV/bin:$PATH" cmake --build "$BUILD" -j2 &&
      PATH="$VENV/bin:$PATH" cmake --install "$BUILD"; } >> "$VENV.msgs-build.log" 2>&1; then
      echo "ros_env.sh: building $PKG failed; the end of $VENV.msgs-build.log:" >&2
      tail -30 "$VENV.msgs-build.log" >&2
      exit 1
    fi
  done
  "$VENV/bin/python" -c "import linkspace_msgs.msg, linkspace_msgs.srv, tf2_msgs.msg" >&2
  echo "$MSG_HASH" > "$VENV/.linkspace-msgs"
fi
hide_from_colcon
echo "$VENV/bin/python"
