"""Pictures: simloop.Renderer on a Sim, and the Gymnasium envs' render modes
(the single and the vector env, Gymnasium's checkers and its rendering
wrappers), with the bad arguments each refuses."""

import warnings

import numpy as np
import pytest
import simloop
from conftest import ROOT, run_python
from simloop.gym import PUSHT_SCENARIO, ScenarioEnv, ScenarioVectorEnv

SIZE = dict(width=96, height=64)
SCENES = ROOT / "tests" / "scenes"


def red(picture):
    """Where the chapter's box is: its red (0.85, 0.3, 0.25), lit or shaded, keeps its ratios."""
    r, g, b = (picture[..., c].astype(int) for c in range(3))
    return (r > 2 * g) & (r > 2 * b)


def mean_column(mask):
    return np.nonzero(mask)[1].mean()


def test_the_chapters_scene_at_rest_has_the_boxs_red_where_the_box_is():
    sim = simloop.Sim()
    renderer = simloop.Renderer(sim, **SIZE)
    picture = renderer.render(sim, track="box")
    assert picture.shape == (64, 96, 3) and picture.dtype == np.uint8
    assert red(picture)[32, 48]
    # From the default free camera the box (x = 0.4) stands right of the pusher (x = 0).
    whole = renderer.render(sim)
    blue = (whole[..., 2].astype(int) > 2 * whole[..., 0]) & (whole[..., 2] > whole[..., 1])
    assert mean_column(red(whole)) > mean_column(blue) + 10
    depth = renderer.render(sim, track="box", distance=1.0, elevation=-90, depth=True)
    assert depth.shape == (64, 96) and depth.dtype == np.float32
    assert depth[32, 48] == pytest.approx(0.95, abs=0.01)  # 1 m above the box's centre, 5 cm above its top


def test_a_picture_shows_the_state_the_sim_has_reached():
    sim = simloop.Sim()
    renderer = simloop.Renderer(sim, **SIZE)
    before = renderer.render(sim, track="pusher", distance=2.0)
    sim.step(500, ctrl=1.0)
    sim.forward()
    after = renderer.render(sim, track="pusher", distance=2.0)
    assert mean_column(red(after)) < mean_column(red(before))  # the box is nearer the pusher once pushed...
    assert red(after).any()
    assert not np.array_equal(before, after)
    assert np.array_equal(after, renderer.render(sim, track="pusher", distance=2.0))  # ...and a picture is repeatable


def test_renderer_arguments_are_checked_with_one_line_each():
    sim = simloop.Sim()
    with pytest.raises(TypeError, match=r"^width must be an int, got '96' \(str\)$"):
        simloop.Renderer(sim, width="96")
    with pytest.raises(ValueError, match=r"^height must be an integer from 1 to 8192, got 0$"):
        simloop.Renderer(sim, height=0)
    renderer = simloop.Renderer(sim, **SIZE)
    with pytest.raises(ValueError, match=r"^no camera named 'top'; the scene has no cameras$"):
        renderer.render(sim, camera="top")
    with pytest.raises(ValueError, match=r"did you mean 'box'\?"):
        renderer.render(sim, track="boxx")
    with pytest.raises(TypeError, match=r"^track must be a str, got 3 \(int\)$"):
        renderer.render(sim, track=3)
    with pytest.raises(ValueError, match=r"^the camera's azimuth must be a finite number of degrees, got nan$"):
        renderer.render(sim, azimuth=float("nan"))
    with pytest.raises(TypeError, match=r"^sim must be a simloop.Sim"):
        renderer.render(object())
    with pytest.raises(ValueError, match=r"another scene"):
        renderer.render(simloop.Sim("tests/scenes/walker.xml"))
    assert renderer.render(sim).shape == (64, 96, 3)  # still usable after each refusal
    with renderer:
        pass
    with pytest.raises(ValueError, match="closed"):
        renderer.render(sim)


def test_a_videos_style_floor_to_the_horizon_no_multisampling_and_a_camera_on_a_point():
    # The box far out, as Break It's hop leaves it (x = 9.1 m): the floor is drawn 2 m out.
    sim = simloop.Sim()
    sim.qpos[:3] = (9.1, 0.0, 0.25)
    sim.forward()
    view = dict(lookat=(9.1, 0.0, 0.05), distance=1.5)
    plain = simloop.Renderer(sim, **SIZE).render(sim, **view)
    video = simloop.Renderer(sim, **SIZE, multisample=False, endless_planes=True).render(sim, **view)
    floor = np.ones((64, 96), bool)
    floor[16:48, 32:64] = False  # around the box
    assert plain[floor].max() < 5  # no floor there: the background
    assert video[floor].min() > 40  # the floor, drawn to the horizon
    assert red(video)[16:30, 42:54].any()  # the box, 20 cm above where the camera looks: above the middle
    assert not red(video)[40:, :].any()
    # Further out than the far clipping plane reaches from the scene's centre (50 times its extent: 34 m), the
    # floor is still under the box: moved under the camera, as MuJoCo moves a plane of no size.
    sim.qpos[:3] = (60.0, 5.0, 0.25)
    sim.forward()
    far = simloop.Renderer(sim, **SIZE, multisample=False, endless_planes=True).render(
        sim, lookat=(60.0, 5.0, 0.05), distance=1.5
    )
    assert far[floor].min() > 40
    assert red(far)[16:30, 42:54].any()
    # At rest, a camera on the box's centre is the camera that tracks it; without
    # multisampling the box's edges change and nothing else.
    sim = simloop.Sim()
    renderer = simloop.Renderer(sim, **SIZE)
    assert np.array_equal(renderer.render(sim, lookat=(0.4, 0.0, 0.05)), renderer.render(sim, track="box"))
    sharp = simloop.Renderer(sim, **SIZE, multisample=False).render(sim, track="box")
    smooth = renderer.render(sim, track="box")
    assert not np.array_equal(sharp, smooth) and red(sharp)[32, 48]
    assert np.mean(np.abs(sharp.astype(int) - smooth)) < 2
    with pytest.raises(ValueError, match=r"^a free camera looks at a body \('box'\) or at a point, not both$"):
        renderer.render(sim, track="box", lookat=(0, 0, 0))
    with pytest.raises(ValueError, match=r"^lookat must be 3 numbers \(x, y, z in metres\), got 2$"):
        renderer.render(sim, lookat=(0, 0))
    with pytest.raises(ValueError, match=r"^the camera's lookat must be 3 finite numbers of metres, got inf$"):
        renderer.render(sim, lookat=(0, float("inf"), 0))
    with pytest.raises(TypeError, match=r"^multisample must be a bool"):
        simloop.Renderer(sim, **SIZE, multisample="no")
    with pytest.raises(ValueError, match=r"^shadow_size must be 64 to 16384 texels, or 0 for 2 a pixel, got 32$"):
        simloop.Renderer(sim, **SIZE, shadow_size=32)
    soft = simloop.Renderer(sim, **SIZE, shadow_size=64).render(sim, track="box")  # the shadow's edge changes
    assert not np.array_equal(soft, smooth) and red(soft)[32, 48]


def test_a_scenes_own_camera_is_drawn_from():
    xml = """<mujoco><worldbody>
      <camera name="above" pos="0 0 2" xyaxes="1 0 0 0 1 0"/>
      <geom type="plane" size="1 1 0.1" rgba="0.5 0.5 0.5 1"/>
      <body pos="0.3 0 0.1"><freejoint/><geom type="box" size="0.1 0.1 0.1" rgba="0.9 0.1 0.1 1"/></body>
    </worldbody></mujoco>"""
    sim = simloop.Sim(simloop.Model.from_xml_string(xml))
    picture = simloop.Renderer(sim, width=101, height=101).render(sim, camera="above")
    # Looking straight down, x to the right: the box is right of the centre, on the middle row.
    assert red(picture)[50].any() and not red(picture)[50, :50].any()
    assert mean_column(red(picture)) > 55


@pytest.fixture
def gymnasium():
    return pytest.importorskip("gymnasium")


def test_each_env_renders_its_state_as_rgb_or_depth(gymnasium):
    env = gymnasium.make("simloop/Chapter-v0", render_mode="rgb_array", **SIZE)
    assert env.metadata["render_fps"] == pytest.approx(10.0)  # a decision every 50 steps of 2 ms
    env.reset(seed=0)
    picture = env.render()
    assert picture.shape == (64, 96, 3) and red(picture)[32, 48]  # Chapter-v0 looks at the box
    depth_env = gymnasium.make("simloop/PushT-v0", render_mode="depth_array", **SIZE)
    depth_env.reset(seed=0)
    depth = depth_env.render()
    assert depth.shape == (64, 96) and depth.dtype == np.float32 and np.isfinite(depth).all() and depth.min() > 0
    assert gymnasium.make("simloop/PushT-v0").unwrapped.render() is None  # no render_mode, no picture


def test_the_vector_envs_pictures_are_the_single_envs(gymnasium):
    seeds = [3, 4]
    envs = ScenarioVectorEnv(
        PUSHT_SCENARIO, 2, control_every=10, render_mode="rgb_array", view={"track": "tblock"}, **SIZE
    )
    singles = [
        ScenarioEnv(PUSHT_SCENARIO, control_every=10, render_mode="rgb_array", view={"track": "tblock"}, **SIZE)
        for _ in seeds
    ]
    envs.reset(seed=seeds)
    for env, seed in zip(singles, seeds):
        env.reset(seed=seed)
    actions = np.random.default_rng(0).uniform(-1, 1, (5, 2, 2))
    for step in actions:
        envs.step(step)
        for env, action in zip(singles, step):
            env.step(action)
    pictures = envs.render()
    assert len(pictures) == 2
    for picture, env in zip(pictures, singles):
        assert np.array_equal(picture, env.render())
    assert not np.array_equal(pictures[0], pictures[1])  # two episodes, two pictures


def test_render_arguments_are_checked_when_the_env_is_made(gymnasium):
    with pytest.raises(
        ValueError,
        match=r"^render_mode must be None or one of 'rgb_array', 'depth_array', "
        r"got 'human' \(str\)$",
    ):
        ScenarioEnv(PUSHT_SCENARIO, render_mode="human")
    with pytest.raises(ValueError, match=r"^view: unknown key 'fov' \(known: 'camera', 'track'"):
        ScenarioEnv(PUSHT_SCENARIO, render_mode="rgb_array", view={"fov": 45})
    with pytest.raises(ValueError, match=r"^no camera named 'top'; the scene has no cameras$"):
        ScenarioVectorEnv(PUSHT_SCENARIO, 2, render_mode="rgb_array", view={"camera": "top"})
    with pytest.raises(ValueError, match=r"^no body named 'tblok' \(did you mean 'tblock'\?\)"):
        ScenarioEnv(PUSHT_SCENARIO, render_mode="rgb_array", view={"track": "tblok"})
    with pytest.raises(ValueError, match=r"^width must be an integer from 1 to 8192, got 0$"):
        ScenarioEnv(PUSHT_SCENARIO, render_mode="rgb_array", width=0)
    # The same without a render mode: a typo fails now, not when one is added.
    with pytest.raises(ValueError, match=r"^no camera named 'top'; the scene has no cameras$"):
        ScenarioEnv(PUSHT_SCENARIO, view={"camera": "top"})
    with pytest.raises(ValueError, match=r"^view: unknown key 'fov'"):
        ScenarioVectorEnv(PUSHT_SCENARIO, 2, view={"fov": 45})
    assert ScenarioEnv(PUSHT_SCENARIO, view={"track": "tblock"}).render() is None
    env = ScenarioEnv(PUSHT_SCENARIO, render_mode="rgb_array", **SIZE)
    with pytest.raises(ValueError, match=r"^reset\(\) the environment before render\(\)$"):
        env.render()
    env.reset(seed=0)
    env.step(env.action_space.sample())
    assert env.render().shape == (64, 96, 3)


def test_checkers_and_rendering_wrappers_take_the_render_modes(gymnasium):
    from gymnasium.utils.env_checker import check_env

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # any remark fails
        for mode in ("rgb_array", "depth_array"):
            check_env(gymnasium.make("simloop/PushT-v0", render_mode=mode, steps=30, **SIZE).unwrapped)
        env = gymnasium.make("simloop/PushT-v0", render_mode="rgb_array", steps=30, **SIZE)  # the passive checker
        env.reset(seed=0)
        assert env.render().shape == (64, 96, 3)
    pixels = gymnasium.wrappers.AddRenderObservation(
        gymnasium.make("simloop/PushT-v0", render_mode="rgb_array", **SIZE), render_only=False
    )
    obs, _ = pixels.reset(seed=0)
    assert obs["pixels"].shape == (64, 96, 3) and pixels.observation_space.contains(obs)
    frames = gymnasium.wrappers.RenderCollection(gymnasium.make("simloop/Chapter-v0", render_mode="rgb_array", **SIZE))
    frames.reset(seed=0)
    for _ in range(3):
        frames.step(frames.action_space.sample())
    assert len(frames.render()) == 4  # the reset's and each step's


def test_gymnasiums_own_vectorizations_render_the_same_pictures(gymnasium):
    """SyncVectorEnv and AsyncVectorEnv (each env in a process of its own, with its own OpenGL context) over the
    single env, and the vector env, draw the same bytes."""
    pictures = {}
    for mode in ("sync", "async", "vector_entry_point"):
        # (this process has rendered: its forked children could not; spawned ones can)
        extra = {"vector_kwargs": {"context": "spawn"}} if mode == "async" else {}
        envs = gymnasium.make_vec(
            "simloop/PushT-v0", num_envs=2, vectorization_mode=mode, render_mode="rgb_array", **SIZE, **extra
        )
        try:
            envs.reset(seed=5)
            envs.step(np.full((2, 2), 0.5))
            pictures[mode] = envs.render()
        finally:
            envs.close()
    for mode in ("async", "vector_entry_point"):
        assert all(np.array_equal(a, b) for a, b in zip(pictures[mode], pictures["sync"])), mode


def test_a_forked_child_of_a_process_that_rendered_is_told_not_left_waiting():
    done = run_python(
        """
        import os, simloop
        sim = simloop.Sim()
        simloop.Renderer(sim, 8, 8).render(sim)
        pid = os.fork()
        if pid == 0:
            try:
                simloop.Renderer(sim, 8, 8)
            except RuntimeError as e:
                print(e, flush=True)
                os._exit(0)
            os._exit(1)
        _, status = os.waitpid(pid, 0)
        print("child", os.waitstatus_to_exitcode(status))
        print(simloop.Renderer(sim, 8, 8).render(sim).shape)  # the parent renders on
    """,
        timeout=60,
    )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == [
        "cannot render in a process forked from one that had already rendered (EGL and its driver's threads do not "
        "survive fork): start worker processes with 'spawn' or 'forkserver' (for Gymnasium's AsyncVectorEnv: "
        "context='spawn')",
        "child 0",
        "(8, 8, 3)",
    ]


def test_renderers_share_one_context_and_small_pictures_take_little_memory():
    # Each renderer had an EGL context and a 640 x 480 multisampled buffer with a 4096 shadow map: 86 MiB of
    # memory and ~70 MiB of address space at any size, so under a 1.5 GB ulimit -v the 57th failed (or crashed).
    done = run_python("""
        import resource, simloop
        resource.setrlimit(resource.RLIMIT_AS, (1500 << 20, 1500 << 20))
        sim = simloop.Sim()
        renderers, first = [], None
        try:
            for i in range(100):
                renderers.append(simloop.Renderer(sim, width=32, height=24))
                picture = renderers[-1].render(sim)
                first = picture if first is None else first
                assert (picture == first).all()
        except RuntimeError as e:
            print("refused:", e)
        print("renderers:", len(renderers))
    """)
    if "cannot render" in done.stdout + done.stderr or "rendering needs EGL" in done.stdout + done.stderr:
        pytest.skip("this machine cannot render")
    assert done.returncode == 0, done.stderr[-2000:]
    assert "renderers: 100" in done.stdout, done.stdout


def test_a_picture_is_the_same_whatever_other_renderers_drew_in_the_shared_context():
    sim = simloop.Sim()
    sim.step(200, ctrl=1.0)
    alone = simloop.Renderer(sim, width=96, height=64).render(sim)
    other = simloop.Sim(SCENES / "walker.xml")
    others = [simloop.Renderer(other, width=200, height=100), simloop.Renderer(sim, width=640, height=480)]
    mine = simloop.Renderer(sim, width=96, height=64)
    for _ in range(2):
        others[0].render(other)
        assert np.array_equal(mine.render(sim), alone)
        others[1].render(sim, track="pusher", distance=3.0)
    assert np.array_equal(mine.render(sim), alone)
