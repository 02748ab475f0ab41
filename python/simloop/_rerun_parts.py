"""The pieces recording.py's Recording logs, as rerun 0.41 draws them: a
scene's geoms as archetypes, a plane as a slab, the camera, the blueprint's
layout, and the rules for the time series' panels (by quantity) and axes.
rerun is imported only inside these functions, as the recorder is made."""

from __future__ import annotations

from typing import Any, Mapping, Optional, Tuple

PLANE_THICKNESS = 0.01
PLANE_MARGIN = 0.5  # how far a plane reaches beyond where the bodies start
# The narrowest a value axis shows: below it rerun labelled a still box's y
# (1e-15 m of rounding on MuJoCo 4) "-0.000 000 000 000 002".
MIN_AXIS_SPAN = 0.01

# A scenario's panels: each column's quantity, by its name and unit, in this order.
QUANTITIES = [
    ("positions (m)", lambda name, unit: unit == "m" and name[-3:] not in ("_qw", "_qx", "_qy", "_qz")),
    ("orientations (quaternion w x y z)", lambda name, unit: name[-3:] in ("_qw", "_qx", "_qy", "_qz")),
    ("velocities (m/s, rad/s)", lambda name, unit: unit.startswith(("m/s", "rad/s"))),
    ("forces (N, N m)", lambda name, unit: unit.startswith("N")),
    ("controls", lambda name, unit: name.endswith("_ctrl")),
    ("contacts", lambda name, unit: name in ("contacts", "ncon")),
    ("the rest", lambda name, unit: True),
]


def _rotate_into_body(quat_wxyz, vectors):
    """Rotates world vectors into each body's frame (by the conjugate quaternion)."""
    import numpy as np

    w = quat_wxyz[:, :1]
    u = -quat_wxyz[:, 1:]  # conjugate: the inverse rotation for a unit quaternion
    t = 2.0 * np.cross(u, vectors)
    return vectors + w * t + np.cross(u, t)


def _rgba(colour) -> list:
    return [int(round(255 * max(0.0, min(1.0, c)))) for c in colour]


def _shape(rr, geom: Mapping[str, Any]):
    """The rerun archetype that draws `geom` in its own frame (a plane: see _plane_slab)."""
    kind, half, colour = geom["kind"], geom["half_size"], [_rgba(geom["rgba"])]
    if kind == "box":
        return rr.Boxes3D(half_sizes=[half], colors=colour, fill_mode="solid")
    if kind == "mesh":
        return rr.Boxes3D(half_sizes=[half], centers=[geom["mesh_center"]], colors=colour, fill_mode="solid")
    if kind in ("sphere", "ellipsoid"):
        return rr.Ellipsoids3D(half_sizes=[half], colors=colour, fill_mode="solid")
    if kind == "capsule":  # rerun's capsule runs from its translation along +z
        return rr.Capsules3D(lengths=[2 * half[2]], radii=[half[0]], translations=[[0, 0, -half[2]]], colors=colour)
    if kind == "cylinder":
        return rr.Cylinders3D(lengths=[2 * half[2]], radii=[half[0]], colors=colour, fill_mode="solid")
    return None  # heightfields and the like: not drawn


def _pose(rr, geom: Mapping[str, Any]):
    w, x, y, z = geom["quat"]
    return rr.Transform3D(translation=geom["pos"], quaternion=[x, y, z, w])


def _plane_slab(geom: Mapping[str, Any], low: Any, high: Any) -> Tuple[list, list]:
    """(centre, half sizes), in the plane's frame, of a slab whose top is the
    plane: the plane's own size, widened to reach PLANE_MARGIN beyond the
    world box [low, high] where the bodies start (None: nowhere finite)."""
    import numpy as np

    hi = np.asarray(geom["half_size"][:2], dtype=float)
    lo = -hi
    if low is not None:
        corners = np.array([[x, y, z] for x in (low[0], high[0]) for y in (low[1], high[1]) for z in (low[2], high[2])])
        local = _rotate_into_body(np.tile(geom["quat"], (len(corners), 1)), corners - geom["pos"])[:, :2]
        lo = np.minimum(lo, local.min(axis=0) - PLANE_MARGIN)
        hi = np.maximum(hi, local.max(axis=0) + PLANE_MARGIN)
    return [*((lo + hi) / 2), -PLANE_THICKNESS / 2], [*((hi - lo) / 2), PLANE_THICKNESS / 2]


def _layout(plots: Any, eye: Any = None) -> Any:
    """The blueprint: the 3D view on the left (its camera `eye`), `plots` on
    the right, on the sim_time timeline."""
    import rerun.blueprint as rrb

    return rrb.Blueprint(
        rrb.Horizontal(
            rrb.Spatial3DView(name="the scene", origin="/world", eye_controls=eye), plots, column_shares=[3, 2]
        ),
        rrb.TimePanel(timeline="sim_time"),
        collapse_panels=False,
    )


def _eye(low: Any, high: Any, tracking: Optional[str] = None) -> Any:
    """A camera on the region [low, high] where the moving bodies start, from
    the front left and above, far enough to see all of it (at least a metre
    across); following `tracking`'s entity if given."""
    import numpy as np
    import rerun.blueprint as rrb

    if low is None:
        return None
    centre = (np.asarray(low) + np.asarray(high)) / 2
    span = max(1.0, float(np.max(np.asarray(high) - np.asarray(low))))
    position = centre + span * np.array([-0.6, -1.2, 0.7])
    return rrb.EyeControls3D(look_target=centre.tolist(), position=position.tolist(), tracking_entity=tracking)


def value_axis_range(span: Optional[Tuple[float, float]]) -> Optional[Tuple[float, float]]:
    """A panel's value axis for series spanning `span` (low, high): None
    (rerun fits the data) unless that is less than MIN_AXIS_SPAN, then that
    span, centred on them."""
    if span is None:
        return None
    low, high = span
    if high - low >= MIN_AXIS_SPAN:
        return None
    middle = (low + high) / 2
    return (middle - MIN_AXIS_SPAN / 2, middle + MIN_AXIS_SPAN / 2)


def z_axis_range(span: Optional[Tuple[float, float]]) -> Tuple[float, float]:
    """The chapter's box z panel: a fixed 0.04 to 0.12 m, so a sound run looks
    flat beside Break It, widened only if the box leaves it."""
    if span is None:
        return (0.04, 0.12)
    return (min(0.04, span[0] - 0.005), max(0.12, span[1] + 0.005))
