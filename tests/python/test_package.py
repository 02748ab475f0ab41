import importlib.metadata
import subprocess
import sys

import simloop
from conftest import sim_loop_exe


def test_one_version_everywhere():
    assert simloop.__version__ == importlib.metadata.version("simloop")
    out = subprocess.run([str(sim_loop_exe()), "--version"], capture_output=True, text=True, check=True).stdout
    assert out == f"sim_loop {simloop.__version__} ({simloop.MUJOCO_VERSION})\n"
    from simloop import _build

    assert simloop.MUJOCO_VERSION == f"MuJoCo {_build.MUJOCO_LIBRARY_VERSION}"  # the library it was built on


def test_public_names_are_importable():
    for name in simloop.__all__:
        assert hasattr(simloop, name), name
    assert len(simloop.COLUMN_NAMES) == 22
    assert simloop.COLUMN_NAMES[:3] == ("step", "time", "ctrl")


def test_result_shape_and_views():
    result = simloop.run(steps=100, record_every=1)
    traj = result.trajectory
    assert traj.shape == (101, 22)
    assert traj.dtype.name == "float64"
    assert not traj.flags.writeable
    # Views into the result's own buffer: no copies.
    column = result.column("box_z")
    assert traj.flags.c_contiguous and not column.flags.writeable
    assert column.base is not None
    assert (column == traj[:, simloop.COLUMN_NAMES.index("box_z")]).all()
    assert list(result.columns) == list(simloop.COLUMN_NAMES)
    assert result.shove.start_step == 50 and result.shove.steps == 50
    assert result.warnings == []
    assert result.timestep == 0.002
    # The view outlives the name it came from.
    del result
    assert column[0] == 0.05


def test_import_simloop_loads_neither_numpy_nor_the_optional_libraries():
    # The command's --no-rerun path and `import simloop` stay quick: numpy
    # (~80 ms), pandas, pyarrow, gymnasium, dask, tqdm, rerun, torch and
    # stable-baselines3 load when used.
    code = (
        "import sys, simloop; heavy = [m for m in ('numpy', 'pandas', 'pyarrow', 'gymnasium', 'dask', 'tqdm',"
        " 'rerun', 'torch', 'stable_baselines3') if m in sys.modules]; print(heavy)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
    assert simloop.BatchTable.__name__ == "BatchTable" and callable(simloop.to_pandas)
