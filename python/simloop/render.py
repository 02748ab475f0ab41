"""simloop.Renderer: pictures of a simulation's state, made without a window.

    renderer = simloop.Renderer(sim.model, width=640, height=480)
    rgb = renderer.render(sim, track="box")            # (480, 640, 3) uint8
    depth = renderer.render(sim, track="box", depth=True)  # (480, 640) float32, metres

MuJoCo's own renderer (mjv_updateScene, mjr_render into its offscreen
framebuffer) on an OpenGL context from EGL: a GPU where there is one, Mesa's
software rasteriser where there is not (Debian: libegl1, libgl1-mesa-dri).
No display or window server is needed. A machine that cannot render raises
RuntimeError saying what to install, when the Renderer is made.

Where the picture is taken from: `camera`, one of the scene's cameras by
name; or a free camera, looking at the whole scene (MuJoCo's default free
camera: the scene's centre, from 1.5 times its extent), or at a body's
subtree centre of mass with `track`, or at a point with `lookat` (x, y, z
in metres, world frame); `distance` (m), `azimuth` and `elevation`
(degrees) move the free camera.

How it draws: multisample=False leaves out MuJoCo's multisampling (edges a
little jagged, a picture about 3 times faster on Mesa's software
rasteriser); endless_planes=True draws planes to the horizon, as the
physics has them, rather than to their size (a body that travels off the
drawn floor still has it under it); shadow_size (texels a side, 64 to
16384) sets the shadow map, about 2 texels a pixel unless given. A video's
frames use all three (512 texels).

A picture shows the poses MuJoCo last computed: a Sim's are as of its last
step (MuJoCo derives them before integrating); sim.forward() brings them
up to date first, without changing the run's bits.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Mapping, Optional, Sequence, Union

if TYPE_CHECKING:
    import numpy as np
    from numpy.typing import NDArray

from . import _core
from ._checks import (
    ModelLike,
    _check_bool,
    _check_int,
    _check_keys,
    _check_real,
    _check_str,
    _describe,
    _reals,
    load_model,
)
from .sim import Sim

MAX_PICTURE_SIZE: int = _core.MAX_PICTURE_SIZE


class CameraSettings:
    """Where pictures are taken from (see the module's documentation),
    checked once: the types here, the names and ranges by the renderer."""

    def __init__(
        self,
        camera: Optional[str] = None,
        track: Optional[str] = None,
        distance: Optional[float] = None,
        azimuth: Optional[float] = None,
        elevation: Optional[float] = None,
        lookat: Optional[Sequence[float]] = None,
    ) -> None:
        self.camera = None if camera is None else _check_str("camera", camera)
        self.track = None if track is None else _check_str("track", track)
        self.distance = None if distance is None else _check_real("distance", distance)
        self.azimuth = None if azimuth is None else _check_real("azimuth", azimuth)
        self.elevation = None if elevation is None else _check_real("elevation", elevation)
        self.lookat = None if lookat is None else _reals("lookat", lookat)
        if self.lookat is not None and len(self.lookat) != 3:
            raise ValueError(f"lookat must be 3 numbers (x, y, z in metres), got {len(self.lookat)}")

    def core(self) -> _core.CameraView:
        return _core.CameraView(self.camera, self.track, self.distance, self.azimuth, self.elevation, self.lookat)

    def __repr__(self) -> str:
        given = {k: v for k, v in vars(self).items() if v is not None}
        return f"CameraSettings({', '.join(f'{k}={v!r}' for k, v in given.items())})"


class Renderer:
    """Offscreen pictures of states of one scene; see the module's documentation.

    model: the scene (a Model, an MJCF path, None for the chapter's, or a
    Sim, whose model it takes). width, height: the pictures' size in pixels,
    1 to MAX_PICTURE_SIZE. Safe to share between threads (pictures take
    turns); close() frees the OpenGL context early.
    """

    def __init__(
        self,
        model: Union[ModelLike, Sim] = None,
        width: int = 640,
        height: int = 480,
        *,
        multisample: bool = True,
        endless_planes: bool = False,
        shadow_size: Optional[int] = None,
    ) -> None:
        scene = model.model if isinstance(model, Sim) else load_model(model)
        self._renderer: Optional[_core.Renderer] = _core.Renderer(
            scene,
            _check_int("width", width, 1, MAX_PICTURE_SIZE),
            _check_int("height", height, 1, MAX_PICTURE_SIZE),
            _check_bool("multisample", multisample),
            _check_bool("endless_planes", endless_planes),
            0 if shadow_size is None else _check_int("shadow_size", shadow_size),
        )
        self.width, self.height = width, height

    def render(
        self,
        sim: Sim,
        *,
        camera: Optional[str] = None,
        track: Optional[str] = None,
        distance: Optional[float] = None,
        azimuth: Optional[float] = None,
        elevation: Optional[float] = None,
        lookat: Optional[Sequence[float]] = None,
        depth: bool = False,
    ) -> "NDArray[np.generic]":
        """A picture of sim's state: (height, width, 3) uint8 RGB, rows from
        the top; with depth=True, (height, width) float32 distances in metres
        from the camera's plane. ValueError for a camera or body the scene
        lacks (naming those it has), a free camera's setting beside a
        scene's camera, or a Sim of another scene."""
        if not isinstance(sim, Sim):
            raise TypeError(f"sim must be a simloop.Sim, got {_describe(sim)}")
        view = CameraSettings(camera, track, distance, azimuth, elevation, lookat).core()
        return self._core().render_sim(sim._sim, view, _check_bool("depth", depth))

    def _core(self) -> _core.Renderer:
        if self._renderer is None:
            raise ValueError("this Renderer is closed")
        return self._renderer

    def close(self) -> None:
        """Frees the OpenGL context now (it is freed with the Renderer otherwise)."""
        self._renderer = None

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"Renderer({self.width}x{self.height}{', closed' if self._renderer is None else ''})"


# What a Gymnasium env's render_mode may be (gym.py): a picture, or its depth.
RENDER_MODES = ("rgb_array", "depth_array")
VIEW_KEYS = ("camera", "track", "distance", "azimuth", "elevation", "lookat")


class EpisodePictures:
    """The pictures of a Gymnasium env's episodes (gym.py): the render mode,
    size and view checked when the env is made (with no render mode too:
    a view with a typo fails then, not when a render mode is added), the
    OpenGL context made at the first picture (an env that never renders
    never loads EGL)."""

    def __init__(
        self, model: _core.Model, render_mode: Optional[str], width: int, height: int, view: Optional[Mapping[str, Any]]
    ) -> None:
        if render_mode is not None and render_mode not in RENDER_MODES:
            raise ValueError(
                f"render_mode must be None or one of {', '.join(map(repr, RENDER_MODES))}, got {_describe(render_mode)}"
            )
        if view is not None and not isinstance(view, Mapping):
            raise TypeError(f"view must be a dict of {', '.join(VIEW_KEYS)}, or None, got {_describe(view)}")
        _check_keys("view", view or {}, VIEW_KEYS)
        self.view = CameraSettings(**(view or {}))
        _core.check_camera_view(model, self.view.core())
        self.model = model
        self.depth = render_mode == "depth_array"
        self.width = _check_int("width", width, 1, MAX_PICTURE_SIZE)
        self.height = _check_int("height", height, 1, MAX_PICTURE_SIZE)
        self._renderer: Optional[_core.Renderer] = None

    def picture(self, episodes: _core.Episodes, i: int) -> "NDArray[np.generic]":
        if self._renderer is None:
            self._renderer = _core.Renderer(self.model, self.width, self.height)
        return self._renderer.render_episode(episodes, i, self.view.core(), self.depth)

    def close(self) -> None:
        self._renderer = None
