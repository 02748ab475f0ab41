"""simloop's Gymnasium environments, registered with Gymnasium once it is
imported: simloop/Chapter-v0, simloop/PushT-v0, simloop/Scenario-v0
(simloop/gym.py, loaded by gymnasium.make through the entry points) and
Gymnasium's v5 tasks as simloop/<Task>-v5 (simloop/gym_tasks.py).
Importing gymnasium here would cost every `import simloop` about 0.15 s, and
nothing happens when it is not installed.
"""

import sys

_GYMNASIUM_IDS = {
    "simloop/Chapter-v0": ("simloop.gym:chapter_env", "simloop.gym:chapter_vector_env"),
    "simloop/PushT-v0": ("simloop.gym:pusht_env", "simloop.gym:pusht_vector_env"),
    "simloop/Scenario-v0": ("simloop.gym:ScenarioEnv", "simloop.gym:ScenarioVectorEnv"),
}
# Gymnasium's MuJoCo v5 tasks over its own XML (simloop/gym_tasks.py), each with Gymnasium's max_episode_steps.
_V5_TASKS = {
    "HalfCheetah": "half_cheetah",
    "Hopper": "hopper",
    "Walker2d": "walker2d",
    "Swimmer": "swimmer",
    "Ant": "ant",
    "Humanoid": "humanoid",
    "HumanoidStandup": "humanoid_standup",
    "InvertedPendulum": "inverted_pendulum",
    "InvertedDoublePendulum": "inverted_double_pendulum",
    "Reacher": "reacher",
    "Pusher": "pusher",
}
_EPISODE_STEPS = {"Reacher": 50, "Pusher": 100}  # (Gymnasium's max_episode_steps where not 1000)


def episode_steps(task: str) -> int:
    """Gymnasium's max_episode_steps for its v5 task."""
    return _EPISODE_STEPS.get(task, 1000)


def register_envs(gymnasium) -> None:  # type: ignore[no-untyped-def]
    for env_id, (entry_point, vector_entry_point) in _GYMNASIUM_IDS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(id=env_id, entry_point=entry_point, vector_entry_point=vector_entry_point)
    for task, function in _V5_TASKS.items():
        if f"simloop/{task}-v5" not in gymnasium.registry:
            gymnasium.register(
                id=f"simloop/{task}-v5",
                entry_point=f"simloop.gym_tasks:{function}",
                vector_entry_point=f"simloop.gym_tasks:{function}_vector",
                max_episode_steps=episode_steps(task),
            )


def register_when_gymnasium_loads() -> None:
    """Registers the environments now if gymnasium is loaded, else as soon as it is."""
    if "gymnasium" in sys.modules:
        register_envs(sys.modules["gymnasium"])
        return
    import importlib.abc  # (only when gymnasium is installed and not loaded yet)
    import importlib.util

    if importlib.util.find_spec("gymnasium") is None:
        return

    class _WhenGymnasiumLoads(importlib.abc.MetaPathFinder):
        finding = False  # importlib.util.find_spec below asks the finders again, this one among them

        def find_spec(self, name, path, target=None):  # type: ignore[no-untyped-def]
            if name != "gymnasium" or self.finding:
                return None
            self.finding = True
            try:
                spec = importlib.util.find_spec(name)
            finally:
                self.finding = False
            if spec is None or spec.loader is None:
                return spec
            execute = spec.loader.exec_module

            def exec_module(module):  # type: ignore[no-untyped-def]
                # Only an import gets here (a program's own find_spec("gymnasium") does not): the hook's
                # one use.
                if self in sys.meta_path:
                    sys.meta_path.remove(self)
                execute(module)
                register_envs(module)

            spec.loader.exec_module = exec_module  # type: ignore[method-assign]
            return spec

    sys.meta_path.insert(0, _WhenGymnasiumLoads())
