# Types of _build.py, which CMake generates from _build.py.in at build time.
MUJOCO_BUILD: str
MUJOCO_LIBRARY_VERSION: str
