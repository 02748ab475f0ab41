#!/usr/bin/env bash
# Installs what simloop needs on Debian 12 and is missing (apt-get, through
# sudo when not root), then builds. Without a flag, the C++ tree (library,
# command, tests, benchmarks). With --python, that and a virtual environment
# with the package and the test tools (pip install ".[test]": scikit-build-core
# builds the module from the same CMake tree). With --package, only the
# virtual environment and the package (pip install .): python -m simloop and
# its recording, without the C++ tests and benchmarks (the first run).
# Called by scripts/run.sh (--package) and scripts/test.sh (--python); safe to rerun.
#
# Which MuJoCo: SIMLOOP_MUJOCO=system (the default) builds on Debian's
# libmujoco-dev 2.2.2 into build/ and .venv; SIMLOOP_MUJOCO=pypi builds on
# the PyPI mujoco package (the version pyproject.toml's `mujoco` extra pins)
# into build-pypi/ and .venv-pypi, which then holds that mujoco too.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
with_python=0 with_tree=1 extras=.[test]
case ${1:-} in
  --python) with_python=1 ;;
  --package) with_python=1 with_tree=0 extras=. ;;
esac

python=${PYTHON:-python3}
mujoco=${SIMLOOP_MUJOCO:-system}
case $mujoco in
  system) build=build venv=.venv ;;
  pypi) build=build-pypi venv=.venv-pypi ;;
  *) echo "setup: SIMLOOP_MUJOCO must be system or pypi, got '$mujoco'" >&2; exit 2 ;;
esac

# libegl-dev: the EGL headers offscreen rendering builds with; libgl1-mesa-dri:
# Mesa's software rasteriser, which draws where there is no GPU.
apt_packages=(libtomlplusplus-dev libegl-dev libgl1-mesa-dri)
if ((with_tree)); then apt_packages+=(libgtest-dev clang-format); fi  # the C++ tests, scripts/lint.sh
if [[ $mujoco == system ]]; then
  # libmujoco-dev's CMake config asks for OpenGL (find_dependency) and its
  # target for /usr/include/libqhull_r, but it depends on neither dev package.
  apt_packages+=(libmujoco-dev libqhull-dev libgl-dev libopengl-dev)
else
  with_venv=1  # the C++ build reads MuJoCo from the venv's mujoco package
fi
command -v g++ >/dev/null 2>&1 || apt_packages+=(g++)
command -v make >/dev/null 2>&1 || command -v ninja >/dev/null 2>&1 || apt_packages+=(make)
command -v cmake >/dev/null 2>&1 || apt_packages+=(cmake)
if ((with_python || ${with_venv:-0})); then
  if ! command -v "$python" >/dev/null 2>&1; then
    apt_packages+=(python3 python3-venv python3-dev)
  else
    "$python" -c "import ensurepip, venv" 2>/dev/null || apt_packages+=(python3-venv)
    "$python" -c "import os, sys, sysconfig; sys.exit(not os.path.exists(os.path.join(sysconfig.get_paths()['include'], 'Python.h')))" \
      || apt_packages+=(python3-dev)
  fi
fi

missing=()
for pkg in "${apt_packages[@]}"; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done
if ((${#missing[@]})); then
  if [[ $(id -u) -eq 0 ]]; then
    sudo=()
  elif command -v sudo >/dev/null 2>&1; then
    sudo=(sudo)
  else
    echo "setup: need root or sudo to install: ${missing[*]}" >&2
    exit 1
  fi
  echo "setup: installing ${missing[*]}"
  "${sudo[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

pip=(-m pip install -q --disable-pip-version-check)
cmake_args=()
if [[ $mujoco == pypi ]]; then
  [[ -x $venv/bin/python ]] || "$python" -m venv "$venv"
  # The one pin: pyproject.toml's `mujoco` extra.
  pin=$("$venv/bin/python" -c "import tomllib; print(tomllib.load(open('pyproject.toml', 'rb'))['project']['optional-dependencies']['mujoco'][0])")
  echo "setup: pip install $pin into $venv"
  "$venv/bin/python" "${pip[@]}" "$pin"
  cmake_args=(-DSIMLOOP_MUJOCO=pypi "-DSIMLOOP_MUJOCO_PYTHON=$PWD/$venv/bin/python")
fi
if ((with_tree)); then
  cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release "${cmake_args[@]}" >/dev/null
  cmake --build "$build" -j "$(nproc)"
fi

# stable-baselines3 (the sb3 extra, for simloop.sb3 and its tests) brings
# torch, gigabytes: only the PyPI build's test install adds it (CI installs it
# once, there); SIMLOOP_SB3=0 leaves it out. torch from PyPI runs on the CPU
# where there is no GPU.
if [[ $mujoco == pypi && $extras == ".[test]" && ${SIMLOOP_SB3:-1} != 0 ]]; then extras=.[test,sb3]; fi
if ((with_python)); then
  [[ -x $venv/bin/python ]] || "$python" -m venv "$venv"
  echo "setup: pip install $extras into $venv (builds the module: a few minutes the first time)"
  SIMLOOP_MUJOCO=$mujoco "$venv/bin/python" "${pip[@]}" "$extras"
fi
