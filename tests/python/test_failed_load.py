"""After a load or compile that fails, the process is as it was: the memory
MuJoCo's compiler had is released and the next call works (MuJoCo 2.2 leaks
the scene it was compiling when its compiler runs out of memory, and leaves
its own error handler behind; the compile now runs in a child process)."""

from conftest import run_python

CHILD = """
    import resource
    import simloop

    def rss_mib():
        with open("/proc/self/status") as status:
            return next(int(line.split()[1]) for line in status if line.startswith("VmRSS:")) / 1024

    xml = simloop._core.PUSHER_SCENE_XML.replace('<compiler autolimits="true"/>',
                                                 '<compiler autolimits="true"/><size nkey="5000000"/>')
    path = "{tmp}/many_keys.xml"
    with open(path, "w") as f:
        f.write(xml)
    falls = "{tmp}/falls.xml"  # a stack too small once the boxes land: a MuJoCo error while stepping
    with open(falls, "w") as f:
        f.write('<mujoco><option timestep="0.004"/><size nstack="600"/><worldbody>'
                '<geom type="plane" size="2 2 0.1"/>'
                '<body name="b1" pos="0 0 0.5"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>'
                '<body name="b2" pos="0.3 0 0.5"><freejoint/><geom type="box" size="0.05 0.05 0.05"/></body>'
                '</worldbody></mujoco>')
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
    proc = run_python(CHILD.format(tmp=tmp_path), timeout=300)
    assert proc.returncode == 0, f"exit {proc.returncode}: {proc.stderr[-2000:]}"
    lines = proc.stdout.splitlines()
    assert len(lines) == 5, proc.stdout
    for line in lines[:3]:
        assert line.startswith("MujocoError ") and "out of memory" in line, line
    words = lines[3].split()
    assert words[:3] == ["next", "run", "11"], lines[3]
    assert int(words[-1]) < 50, f"{lines[3]}: MiB the failed compiles kept"
    assert lines[4].startswith("stepping error ") and "Stack overflow" in lines[4], lines[4]
