#!/usr/bin/env bash
# Installs what simloop needs on Debian 12 and is missing (apt-get, through
# sudo when not root), then builds the C++ tree into build/. With --python,
# also makes the virtual environment .venv and installs the package into it
# (pip install ".[test]": scikit-build-core builds the module from the same
# CMake tree). Called by scripts/run.sh and scripts/test.sh; safe to rerun.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
with_python=0
[[ ${1:-} == --python ]] && with_python=1

python=${PYTHON:-python3}
# libmujoco-dev's CMake config asks for OpenGL (find_dependency) and its target
# for /usr/include/libqhull_r, but the package depends on neither dev package.
apt_packages=(libmujoco-dev libqhull-dev libgl-dev libopengl-dev libtomlplusplus-dev libgtest-dev)
command -v g++ >/dev/null 2>&1 || apt_packages+=(g++)
command -v make >/dev/null 2>&1 || command -v ninja >/dev/null 2>&1 || apt_packages+=(make)
command -v cmake >/dev/null 2>&1 || apt_packages+=(cmake)
if ((with_python)); then
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

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$(nproc)"

if ((with_python)); then
  [[ -x .venv/bin/python ]] || "$python" -m venv .venv
  echo "setup: pip install .[test] into .venv"
  .venv/bin/python -m pip install -q --disable-pip-version-check ".[test]"
fi
