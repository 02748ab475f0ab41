"""After a load or compile that fails, the process is as it was: the memory
MuJoCo's compiler had is released and the next call works (MuJoCo 2.2 leaks
the scene it was compiling when its compiler runs out of memory, and leaves
its own error handler behind; the compile now runs in a child process)."""

from conftest import run_python
from expected import expected, stepping_error_scene

CHILD = """
    import resource
    import simloop

    def rss_mib():
        with open("/proc/self/status") as status:
            return next(int(line.split()[1]) for line in status if line.startswith("VmRSS:")) / 1024

    xml = simloop._core.PUSHER_SCENE_XML.replace('<compiler autolimits="true"/>',
                                                 '<compiler autolimits="true"/>' + {too_big!r})
    path = "{tmp}/many_keys.xml"
    with open(path, "w") as f:
        f.write(xml)
    falls = "{tmp}/falls.xml"  # a MuJoCo error while stepping
    with open(falls, "w") as f:
        f.write({falls!r})
    simloop.run(steps=10)
    before = rss_mib()
    resource.setrlimit(resource.RLIMIT_AS, (1000000 * 1024, resource.RLIM_INFINITY))  # ulimit -v 1000000
    for load in (lambda: simloop.Model.from_file(path), lambda: simloop.Model.from_xml_string(xml, "many_keys"),
                 lambda: simloop.Sim(path)):
        try:
            load()
            print("loaded")
        except (simloop.MujocoError, MemoryError) as e:
            print(type(e).__name__, e)
    print("next run", simloop.run(steps=10).rows, "rss grew", round(rss_mib() - before))
    try:
        simloop.run_scenario(simloop.Scenario(scene=falls, steps=2000, disturbances=[]))
    except simloop.MujocoError as e:
        print("stepping error", e)
"""


def test_a_compile_that_runs_out_of_memory_leaves_the_process_as_it_was(tmp_path):
    falls, stepping_error = stepping_error_scene()
    says = expected("errors.out_of_memory_says")
    proc = run_python(
        CHILD.format(tmp=tmp_path, too_big=expected("errors.out_of_memory_scene"), falls=falls), timeout=300
    )
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    assert proc.stderr == "", proc.stderr  # what the compiling child said is in the error, not on stderr
    lines = proc.stdout.splitlines()
    assert len(lines) == 5, proc.stdout
    for line in lines[:3]:
        assert line.startswith("MujocoError ") and any(said in line for said in says), line
    words = lines[3].split()
    assert words[:3] == ["next", "run", "11"], lines[3]
    assert int(words[-1]) < 50, f"{lines[3]}: MiB the failed compiles kept"
    assert lines[4].startswith("stepping error ") and stepping_error in lines[4], lines[4]
