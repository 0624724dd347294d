"""Drawing helpers shared by the three-body scenes (collinear, syzygy, lunar-perturbation).

Everything drawn is read from the Run: body positions (`trajectory.bodies`), the angle of the
frame turning with the bodies (`trajectory.series["frame_angle_rad"]`), the co-rotating and
element series, the zero-velocity grid and the Lagrange points (`run.extras`). The only
computations here are drawing geometry: a rotation of positions into the co-rotating frame,
contour lines of the physics' grid (marching squares), and scaling to scene units.

A scene that can be seen from the inertial frame or from the frame turning with the bodies draws
its construction lines (the line of the bodies, the Sun line, the Lagrange points) in the turning
frame's coordinates, as children of the Frame `TURNING` ("turning/..."): in the inertial view that
Frame turns by the physics' angle at every frame, in the co-rotating view it stands still and the
bodies are drawn in co-rotating coordinates instead.
"""
from __future__ import annotations

from typing import Sequence

import numpy as np

from .drawing import Drawing, Frame, Label, ORBIT_RADIUS, Option, Path, Segments, Sphere, View, body_name, other_bodies

TURNING = "turning"  # the Frame whose children are drawn in co-rotating coordinates
MARKER_COLOR = (250, 250, 255)
LINE_COLOR = (150, 150, 165)
SUN_LINE_COLOR = (240, 200, 60)
FRAME_ANGLE = "frame_angle_rad"


def corotating_option(default: bool, label: str) -> dict[str, Option]:
    return {"corotating": Option(label, default)}


def rot_z(theta) -> np.ndarray:
    """wxyz quaternions of rotations by theta (N,) about z: (N, 4)."""
    th = np.asarray(theta, float)
    z = np.zeros_like(th)
    return np.stack([np.cos(th / 2), z, z, np.sin(th / 2)], -1)


def rot_zx(psi, inc) -> np.ndarray:
    """wxyz of R_z(psi)·R_x(inc) for arrays psi, inc (N,): takes z to the normal
    (sin i sin ψ, −sin i cos ψ, cos i) of a plane with ascending node at longitude ψ and
    inclination i, and x to the node direction. (N, 4)."""
    psi, inc = np.asarray(psi, float), np.asarray(inc, float)
    cz, sz = np.cos(psi / 2), np.sin(psi / 2)
    cx, sx = np.cos(inc / 2), np.sin(inc / 2)
    return np.stack([cz * cx, cz * sx, sz * sx, sz * cx], -1)


def to_corotating(pos, theta) -> np.ndarray:
    """Positions (N, 3) seen from the frame turned by theta(t) (N,) about z."""
    pos = np.asarray(pos, float)
    c, s = np.cos(theta), np.sin(theta)
    out = np.array(pos, float, copy=True)
    out[:, 0] = c * pos[:, 0] + s * pos[:, 1]
    out[:, 1] = -s * pos[:, 0] + c * pos[:, 1]
    return out


def contour_segments(x: np.ndarray, y: np.ndarray, Z: np.ndarray, level: float) -> np.ndarray:
    """Line segments (M, 2, 3) of the level set Z = level on the grid Z[j, i] at (x[i], y[j])
    (marching squares, linear interpolation on the cell edges; a saddle cell gets two segments
    paired by edge order), at z = 0."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    F = np.asarray(Z, float) - level
    f00, f01, f11, f10 = F[:-1, :-1], F[:-1, 1:], F[1:, 1:], F[1:, :-1]
    X0, Y0 = np.meshgrid(x[:-1], y[:-1])
    X1, Y1 = np.meshgrid(x[1:], y[1:])

    def cut(a, b):
        ok = np.isfinite(a) & np.isfinite(b) & ((a > 0) != (b > 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.where(ok, a / (a - b), 0.5)
        return ok, u

    edges = []  # bottom, right, top, left: (mask, px, py)
    ok, u = cut(f00, f01)
    edges.append((ok, X0 + u * (X1 - X0), Y0))
    ok, u = cut(f01, f11)
    edges.append((ok, X1, Y0 + u * (Y1 - Y0)))
    ok, u = cut(f10, f11)
    edges.append((ok, X0 + u * (X1 - X0), Y1))
    ok, u = cut(f00, f10)
    edges.append((ok, X0, Y0 + u * (Y1 - Y0)))
    M = np.stack([e[0] for e in edges], -1)
    P = np.stack([np.stack([e[1], e[2]], -1) for e in edges], -2)  # (ny-1, nx-1, 4, 2)
    cnt = M.sum(-1)
    segs = []
    two = cnt == 2
    if np.any(two):
        order = np.argsort(~M[two], axis=-1, kind="stable")[:, :2]  # the two cut edges
        p = P[two]
        r = np.arange(len(p))
        segs.append(np.stack([p[r, order[:, 0]], p[r, order[:, 1]]], 1))
    four = cnt == 4
    if np.any(four):
        p = P[four]
        segs += [np.stack([p[:, 0], p[:, 1]], 1), np.stack([p[:, 2], p[:, 3]], 1)]
    if not segs:
        return np.zeros((0, 2, 3), np.float32)
    s2 = np.concatenate(segs)
    return np.concatenate([s2, np.zeros(s2.shape[:2] + (1,))], -1).astype(np.float32)


def corotating(run, spec, view: View) -> bool:
    """The co-rotating view is chosen and the run says how its frame turns."""
    return view.option("corotating", spec) and FRAME_ANGLE in run.trajectory.series


def frame_angle(run) -> np.ndarray:
    """The angle of the frame turning with the bodies at every sample (zeros: a frame that does not turn)."""
    tr = run.trajectory
    return np.asarray(tr.series.get(FRAME_ANGLE, np.zeros(len(tr.t))), float)


def body_positions(run, skip: Sequence[str] = (), turn: bool = False) -> dict[str, np.ndarray]:
    """The run's bodies (trajectory units) without `skip`, in co-rotating coordinates when `turn`."""
    tr = run.trajectory
    out = {k: np.asarray(v, float) for k, v in tr.bodies.items() if k not in skip}
    if turn:
        th = frame_angle(run)
        out = {k: to_corotating(v, th) for k, v in out.items()}
    return out


def largest_distance(bodies: dict[str, np.ndarray]) -> float:
    if not bodies:
        return 1.0
    r = max(float(np.nanmax(np.linalg.norm(v, axis=1))) for v in bodies.values())
    return r if np.isfinite(r) and r > 0 else 1.0


def draw_bodies(d: Drawing, run, bodies: dict[str, np.ndarray], span: float, trails=lambda name: True,
                unnamed: Sequence[str] = ()) -> float:
    """The bodies as balls with names and trails at the scale that draws `span` at ORBIT_RADIUS;
    returns that scale (scene units per trajectory unit). The bodies in `unnamed` get no name
    beside them (one that would sit on other labels: the scene names it elsewhere)."""
    if not bodies:
        return ORBIT_RADIUS / span
    k = other_bodies(d, run, bodies, span=span, trails=trails, directions=False)
    drop = {f"bodies/{n}/label" for n in unnamed}
    d.items = [it for it in d.items if it.name not in drop]
    return k


def colour_name(rgb) -> str:
    """A plain name for a body's colour (for a key that names bodies by colour)."""
    import colorsys

    h, s, v = colorsys.rgb_to_hsv(*(c / 255 for c in rgb))
    if s < 0.2:
        return "white" if v > 0.8 else "grey"
    for top, name in ((0.04, "red"), (0.10, "orange"), (0.19, "yellow"), (0.47, "green"), (0.54, "cyan"),
                      (0.70, "blue"), (0.85, "purple"), (0.95, "pink"), (1.01, "red")):
        if h < top:
            return name
    return "red"


def body_key(d: Drawing, names: Sequence[str], position) -> None:
    """One label naming bodies by their colour ("yellow: primary · green: secondary"), for a scene
    whose bodies would put their names on other labels."""
    colours = {it.name.split("/", 1)[1]: it.color for it in d.items if isinstance(it, Sphere) and
               it.name.startswith("bodies/") and it.name.count("/") == 1}
    text = " · ".join(f"{colour_name(colours[n])}: {body_name(n)}" for n in names if n in colours)
    if text:
        d.add(Label(name="body_key", text=text, position=np.asarray(position, float)))


def turning_frame(d: Drawing, run, corot: bool) -> None:
    """The Frame TURNING: still in the co-rotating view, turned by the frame angle in the inertial one."""
    if corot or FRAME_ANGLE not in run.trajectory.series:
        d.add(Frame(name=TURNING))
    else:
        d.add(Frame(name=TURNING, wxyz=rot_z(frame_angle(run)[d.frames])))


def marker(d: Drawing, name: str, position, radius: float = 0.05, color=MARKER_COLOR) -> None:
    d.add(Sphere(name=name, radius=radius, color=color, position=np.asarray(position, float)))


def line(d: Drawing, name: str, a, b, color=LINE_COLOR, thickness: float = 0.006) -> None:
    d.add(Segments(name=name, points=np.array([[a, b]], np.float32), colors=color, thickness=thickness))


def readout(d: Drawing, texts: list[str], position) -> None:
    """A read-out that follows playback: one string per frame."""
    d.add(Label(name="readout", text=list(texts), position=np.asarray(position, float)))


def growing_path(d: Drawing, name: str, points, samples, color, thickness: float) -> None:
    """A path of points at trajectory `samples` that grows as the run plays."""
    if len(points) >= 2:
        d.add(Path(name=name, points=np.asarray(points, float), color=color, thickness=thickness,
                   at=d.frame_of_sample(samples)))
