"""The camera families: field of view, aspect ratio, pixel-centre offset and rotation, another camera model (a
cylindrical, equirectangular or fisheye camera, a radial lens distortion), fitted by warping a finer image."""

from __future__ import annotations

import math
from dataclasses import replace
from functools import partial

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.basis import SUB, Basis
from mcrt.grade.explain.fit import Fit, refine
from mcrt.grade.feedback import num as _num


def _rot(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Rotation of camera-frame directions (x right, y up, z forward): yaw left, pitch up, roll, in degrees."""
    a, b, c = (math.radians(t) for t in (yaw, pitch, roll))
    Ry = np.array([[math.cos(a), 0, -math.sin(a)], [0, 1, 0], [math.sin(a), 0, math.cos(a)]])
    Rx = np.array([[1, 0, 0], [0, math.cos(b), math.sin(b)], [0, -math.sin(b), math.cos(b)]])
    Rz = np.array([[math.cos(c), -math.sin(c), 0], [math.sin(c), math.cos(c), 0], [0, 0, 1]])
    return Ry @ Rx @ Rz


class _Warp:
    r"""The image of a pinhole camera with another field of view, rotation or pixel-centre offset.

    A student pixel's sample (i + (s + 1/2)/SUB + dx, j + ...) is a
    direction in the student's camera frame,
    :math:`d = (s_x t_s, a\, s_y t_s h/w, 1)` with :math:`t = \tan(fov/2)` and
    :math:`a` the aspect's error (1: square pixels, as the scene's camera has);
    rotated into the scene's camera frame it projects to the scene camera's
    film, where the FINE times finer (and WIDE times wider) image is sampled bilinearly; the SUB^2
    samples of a pixel are averaged (its box filter). Exact for a pinhole (a
    rotation about the eye is a homography) up to the interpolation. The
    model image is ``image(...) - identity``, added to the reference.
    """

    def __init__(self, b: Basis):
        from scipy.ndimage import map_coordinates

        self.map = map_coordinates
        self.F = [np.ascontiguousarray(b.fine[..., c], dtype=np.float32) for c in range(3)]
        self.Hf, self.Wf = b.fine.shape[:2]
        self.h, self.w = b.base.shape[:2]
        self.t = math.tan(math.radians(b.fov_deg) / 2)
        self.tf = b.fine_tan
        jj, ii = np.mgrid[0:self.h * SUB, 0:self.w * SUB]
        self.u, self.v = (ii + 0.5) / SUB, (jj + 0.5) / SUB  # in grade pixels
        self.identity = self.image()

    def image(self, fov: float | None = None, yaw=0.0, pitch=0.0, roll=0.0, dx=0.0, dy=0.0, aspect=1.0) -> np.ndarray:
        return self.at(self.u + dx, self.v + dy, fov, yaw, pitch, roll, aspect)

    def at(self, u: np.ndarray, v: np.ndarray, fov: float | None = None, yaw=0.0, pitch=0.0, roll=0.0,
           aspect=1.0, project=None) -> np.ndarray:
        """The image whose pixel (i, j) is the mean over samples (u, v)[j SUB:(j+1) SUB, i SUB:(i+1) SUB], given in
        grade pixels of the scene's film (the other arguments as for :meth:`image`). ``project(sx, sy, t, t_y)``
        gives another camera model's ray (x, y, z) in the camera frame for film coordinates in [-1, 1] and the
        half-width's and half-height's tangents (default: the pinhole's (sx t, sy t_y, 1))."""
        ts = self.t if fov is None else math.tan(math.radians(fov) / 2)
        asp = aspect * self.h / self.w
        sx = 2 * u / self.w - 1
        sy = 1 - 2 * v / self.h
        R = _rot(yaw, pitch, roll)
        x, y, z = (sx * ts, sy * ts * asp, 1.0) if project is None else project(sx, sy, ts, ts * asp)
        X = R[0, 0] * x + R[0, 1] * y + R[0, 2] * z
        Y = R[1, 0] * x + R[1, 1] * y + R[1, 2] * z
        Z = np.maximum(R[2, 0] * x + R[2, 1] * y + R[2, 2] * z, 1e-9)
        px = (X / Z / self.tf + 1) * self.Wf / 2 - 0.5
        py = (1 - Y / Z / (self.tf * self.Hf / self.Wf)) * self.Hf / 2 - 0.5
        coords = np.stack([py.ravel(), px.ravel()])
        out = np.stack([self.map(f, coords, order=1, mode="nearest").reshape(py.shape) for f in self.F], axis=-1)
        return out.reshape(self.h, SUB, self.w, SUB, 3).mean(axis=(1, 3), dtype=np.float64)


#: The camera families: parameter names, start scans, finite-difference steps, bounds.
_CAMERA = {
    "fov": (("fov",), {"fov": (0.62, 0.72, 0.78, 0.9, 0.95, 1.05, 1.1)}, {"fov": 0.2}, {"fov": (0.55, 1.2)}),
    "pixel_offset": (("dx", "dy"), {"dx": (-1.0, -0.5, 0.5, 1.0), "dy": (-1.0, -0.5, 0.5, 1.0)},
                     {"dx": 0.1, "dy": 0.1}, {"dx": (-2.0, 2.0), "dy": (-2.0, 2.0)}),
    "rotation": (("yaw", "pitch", "roll"), {"yaw": (-4.0, -2.0, -1.0, 1.0, 2.0, 4.0), "pitch": (-4.0, -2.0, -1.0, 1.0, 2.0, 4.0),
                                            "roll": (-6.0, -3.0, 3.0, 6.0)},
                 {"yaw": 0.1, "pitch": 0.1, "roll": 0.2}, {"yaw": (-10, 10), "pitch": (-10, 10), "roll": (-20, 20)}),
}


def _fit_camera(fit: Fit, wp: _Warp, family: str, fov0: float, steps: int = 4) -> tuple[dict, float, np.ndarray]:
    r"""Fit one camera family: a scan of each parameter alone for a start, then Gauss-Newton steps.

    Each step solves :math:`(J^T W J)\,\delta = J^T W r` with J by central
    differences and W the capped chi^2's weights (:meth:`Fit.irls`); a step
    that does not lower chi^2 is halved, twice at most.
    """
    names, scans, h, bounds = _CAMERA[family]
    scale = {"fov": fov0}

    def kw(p):
        return {n: p[i] for i, n in enumerate(names)}

    def img(p):
        return wp.image(**kw(p)) - wp.identity

    p = np.array([fov0 if n == "fov" else 0.0 for n in names])
    best = fit.delta(img(p))
    for i, n in enumerate(names):
        for v in scans[n]:
            q = p.copy()
            q[i] = v * scale.get(n, 1.0)
            c = fit.delta(img(q))
            if c < best:
                best, p = c, q
    lo = np.array([bounds[n][0] * scale.get(n, 1.0) for n in names])
    hi = np.array([bounds[n][1] * scale.get(n, 1.0) for n in names])
    for _ in range(steps):
        m = img(p)
        J = []
        for i, n in enumerate(names):
            e = np.zeros_like(p)
            e[i] = h[n]
            J.append(((img(p + e) - img(p - e)) / (2 * h[n])).ravel())
        J = np.stack(J, axis=1)
        wv = fit.irls(m).ravel()
        r = (fit.D - m).ravel()
        A = J.T @ (J * wv[:, None])
        g = J.T @ (wv * r)
        try:
            d = np.linalg.solve(A + 1e-9 * np.trace(A) * np.eye(len(p)), g)
        except np.linalg.LinAlgError:
            break
        for _ in range(3):
            q = np.clip(p + d, lo, hi)
            c = fit.delta(img(q))
            if c < best:
                best, p = c, q
                break
            d = d / 2
        else:
            break
    return kw(p), best, img(p)


def _diagonal(fov: float, f0: float, shape) -> str:
    """Words for a field of view that is the scene's taken as the image's diagonal one ('' where it is not)."""
    h, w = shape[:2]
    diag = math.degrees(2 * math.atan(math.tan(math.radians(f0) / 2) * w / math.hypot(w, h)))
    return (f" (the {_num(f0)} degrees taken as the image's diagonal field of view: {diag:.1f} across)"
            if abs(fov - diag) <= 0.02 * diag else "")


def _cropped(fov: float, f0: float, shape) -> str:
    """Words for a narrower field of view as the middle of a larger render at the scene's ('' for a wider one): the
    same view, by the pinhole's proportions (the image plane's half-width is tan(fov / 2))."""
    h, w = shape[:2]
    r = math.tan(math.radians(fov) / 2) / math.tan(math.radians(f0) / 2)
    if r > 0.97:
        return ""
    return (f", or the same view as the middle {w} x {h} pixels of a {round(w / r)} x {round(h / r)} render at "
            f"{_num(f0)} degrees (a larger render cropped)")


def _shift_causes(dx: float, dy: float) -> str:
    """What shifts an image by (dx, dy) pixels: a whole pixel is an index off by one, a fraction the pixel centres or
    the sub-pixel offsets (samples spread over [0, s) with s != 1 have their mean s / 2 off the centre)."""
    whole = max(abs(dx), abs(dy)) >= 0.75 and all(abs(v - round(v)) <= 0.1 for v in (dx, dy))
    return ("rows or columns are written one place off (a row or column index off by one), or pixel centres are "
            "off by a pixel" if whole else "pixel centres are not at (i + 0.5, j + 0.5), each pixel's sub-pixel "
            "offsets are not spread over 0 to 1 (their mean off its centre), or an image resampled with an offset, or the "
            "camera a little off (turned, or its eye moved sideways, by that fraction of a pixel)")


#: The aspects a program hard-codes (height over width of a common screen or photo, either way round): the aspect
#: family takes only these. A free factor fits any small change near 1 (a light a little lower stretches the light's
#: image) with no aspect a program would have.
ASPECTS = {"16:9": 9 / 16, "16:10": 10 / 16, "3:2": 2 / 3, "4:3": 3 / 4, "5:4": 4 / 5, "4:5": 5 / 4, "3:4": 4 / 3,
           "2:3": 3 / 2, "10:16": 16 / 10, "9:16": 16 / 9}


def _aspect(fit: Fit, wp: _Warp) -> Candidate:
    """The best of :data:`ASPECTS`: the rays' vertical component scaled by it."""
    best = None
    for name, a in ASPECTS.items():
        dm = wp.image(aspect=a) - wp.identity
        chi = fit.delta(dm)
        if best is None or chi < best[0]:
            best = (chi, name, a, dm)
    chi, name, a, dm = best
    return Candidate("aspect", "aspect ratio", f"the image's height spanning {_num(a)} times the view the field of "
                     f"view gives it (rays' vertical component scaled: an aspect ratio of {name} hard-coded, or the "
                     "width and height swapped in it)", chi, 1, value=a, change=dm)


#: The ratios k of the image's rows (columns) to the count hard-coded in their mapping to the image plane, scanned:
#: below 1 a larger count (only the top, or left, part of the view), above it a smaller one, as far as the fine
#: image reaches; within :data:`COUNT_NEAR` of 1 the field of view says it.
COUNTS = tuple(np.round(np.arange(0.3, 1.125, 0.025), 3))
COUNT_NEAR = 0.05


def _one_axis_count(fit: Fit, wp: _Warp) -> list[Candidate]:
    """The rows (columns) mapped to the image plane with another count than the image's hard-coded, ``t = 1 - 2 (j +
    v) / N`` (``s = 2 (i + u) / N - 1``): the view anchored at the top (left) edge, scaled by k = H / N along that
    axis alone; k scanned (one parameter)."""
    out = []
    for axis, word, edge in (("v", "rows", "top"), ("u", "columns", "left")):
        best = None
        for k in COUNTS:
            if abs(k - 1.0) < COUNT_NEAR:
                continue
            u, v = (wp.u, wp.v * k) if axis == "v" else (wp.u * k, wp.v)
            dm = wp.at(u, v) - wp.identity
            chi = fit.delta(dm)
            if best is None or chi < best[0]:
                best = (chi, float(k), dm)
        chi, k, dm = best
        part = (f"only the {edge} {_num(100 * k)} % of the view, stretched over the image" if k < 1 else
                f"{_num(100 * k)} % of the view from the {edge} edge, squeezed into the image")
        out.append(Candidate("aspect", f"{word} mapped with another count", f"the {word} mapped to the image plane "
                             f"with another count than the image's hard-coded (N = {_num(1 / k)} times the image's "
                             f"{word} in {'t = 1 - 2 (j + v) / N' if axis == 'v' else 's = 2 (i + u) / N - 1'}): "
                             f"{part}", chi, 1, value={"axis": word, "ratio": k}, change=dm))
    return out


def _cylindrical(sx, sy, t, ty):
    """The horizontal angle linear in the column (a cylinder's film), the height as the pinhole's at the centre."""
    a = sx * math.atan(t)
    return np.sin(a), sy * ty, np.cos(a)


def _equirectangular(sx, sy, t, ty):
    """Both angles linear in the pixel (longitude and latitude), spanning the pinhole's field of view."""
    a, e = sx * math.atan(t), sy * math.atan(ty)
    return np.sin(a) * np.cos(e), np.sin(e), np.cos(a) * np.cos(e)


def _fisheye(sx, sy, t, ty):
    """The angle from the axis linear in the distance from the image's centre (an equidistant fisheye), the pinhole's
    horizontal field of view across."""
    r = np.hypot(sx, sy * ty / t)
    theta = r * math.atan(t)
    k = np.where(r > 0, np.sin(theta) / np.maximum(r, 1e-12), math.atan(t))
    return k * sx, k * sy * ty / t, np.cos(theta)


#: Camera models a program implements instead of the pinhole: key -> (words, ray of film coordinates).
PROJECTIONS = {
    "cylindrical": ("a cylindrical panorama: the horizontal angle linear in the column (not its tangent)", _cylindrical),
    "equirectangular": ("an equirectangular (latitude-longitude) camera: both angles linear in the pixel (not their "
                        "tangents)", _equirectangular),
    "fisheye": ("an equidistant fisheye: the angle from the view's centre linear in the distance from the image's "
                "centre", _fisheye),
}
#: Radial distortion coefficients scanned (the film point scaled by 1 + k r^2, r^2 = sx^2 + sy^2): k > 0 a barrel.
RADIAL = tuple(np.round(np.arange(-0.3, 0.31, 0.025), 3))


def _projection(fit: Fit, wp: _Warp) -> list[Candidate]:
    """Each of :data:`PROJECTIONS` (no parameter), and a radial lens distortion (k scanned, refined by a parabola):
    in the camera's rays, or applied to the finished image (each pixel resampled bilinearly, as a lens effect for the
    look is)."""
    out = []
    for key, (words, f) in PROJECTIONS.items():
        dm = wp.at(wp.u, wp.v, project=f) - wp.identity
        out.append(Candidate("camera_model", key, f"the camera {words}, where the assignment's is a pinhole", fit.delta(dm),
                             0, value=key, change=dm))

    def rays(k):
        return wp.at(wp.u, wp.v, project=lambda sx, sy, t, ty: (sx * t * (1 + k * (sx * sx + sy * sy)),
                                                                 sy * ty * (1 + k * (sx * sx + sy * sy)), 1.0)) - wp.identity

    for where, img in (("in the camera's rays", rays), ("applied to the finished image", partial(_radial_image, fit))):
        ks = [k for k in RADIAL if k != 0]
        errs = [fit.delta(img(k)) for k in ks]
        i = int(np.argmin(errs))
        k = float(refine(np.asarray(ks), np.asarray(errs), i))
        dm = img(k)
        kind = "a barrel distortion (the edges drawn in)" if k > 0 else "a pincushion distortion (the edges pushed out)"
        out.append(Candidate("camera_model", f"radial distortion {where}", f"a lens's radial distortion {where}, "
                             f"{kind}: each pixel showing what lies at 1 {'+' if k > 0 else '-'} {_num(abs(k))} r^2 "
                             "times its distance r from the centre (1 at the middle of a side)", fit.delta(dm), 1,
                             value=k, change=dm))
    return out


def _radial_image(fit: Fit, k: float) -> np.ndarray:
    """The reference resampled bilinearly at radius r (1 + k r^2) about the image's centre, minus the reference."""
    from scipy.ndimage import map_coordinates

    R = fit.R
    h, w = R.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    ny, nx = (yy - (h - 1) / 2) / (h / 2), (xx - (w - 1) / 2) / (w / 2)
    f = 1.0 + k * (nx * nx + ny * ny)
    coords = np.stack([(h - 1) / 2 + ny * f * h / 2, (w - 1) / 2 + nx * f * w / 2])
    return np.stack([map_coordinates(R[..., c], coords, order=1, mode="nearest") for c in range(3)], axis=-1) - R


def camera(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The camera's field of view, its aspect, a pixel-centre offset, a rotation: each fitted by warping the fine image."""
    b = inputs.basis
    wp = _Warp(b)
    f0 = b.fov_deg
    out = []
    p, chi, dm = _fit_camera(fit, wp, "fov", f0)
    out.append(Candidate("fov", "field of view", f"the camera's field of view {p['fov']:.1f} degrees where the scene "
                         f"says {_num(f0)}{_diagonal(float(p['fov']), f0, b.base.shape)}"
                         f"{_cropped(float(p['fov']), f0, b.base.shape)}", chi, 1,
                         value=float(p["fov"]), change=dm))
    out.append(_aspect(fit, wp))
    out += _one_axis_count(fit, wp)
    p, chi, dm = _fit_camera(fit, wp, "pixel_offset", f0)
    dx, dy = float(p["dx"]), float(p["dy"])
    # Pixel i shows what lies at i + dx: what the image shows moves by -dx (the camera criterion's sign).
    out.append(Candidate("pixel_offset", "pixel-centre offset", f"the image shifted by ({-dx:+.2f}, {-dy:+.2f}) pixel "
                         f"(x right, y down), as when {_shift_causes(dx, dy)}", chi, 2, value=(dx, dy), change=dm))
    p, chi, dm = _fit_camera(fit, wp, "rotation", f0)
    ya, pi_, ro = (float(p[k]) for k in ("yaw", "pitch", "roll"))
    out.append(Candidate("rotation", "camera rotation", f"the camera rotated by yaw {ya:+.1f}, pitch {pi_:+.1f} and roll "
                         f"{ro:+.1f} degrees (left, up and anticlockwise positive), as when its forward or up vector is "
                         "off", chi, 3, value=(ya, pi_, ro), change=dm))
    return out + _projection(fit, wp)



camera.name = "camera"


#: The image plane's full width 2 tan(fov / 2) taken for its half-width: the field of view's tangent doubled, beyond
#: what the warp of the fine image reaches (narrower views it reaches; at 90 degrees the angle not halved is 180).
PLANE_FACTOR = 2.0
#: Fields of view wider than this (degrees) are not rendered: no pinhole reaches 180.
WIDEST = 170.0


def _prepare_plane(a, scene, render) -> tuple[float, np.ndarray] | None:
    """(the field of view of :data:`PLANE_FACTOR`, its render at the basis's spp and seed), or None past
    :data:`WIDEST`."""
    from mcrt.grade.explain.basis import basis_renderer

    c0 = scene.cameras[a.camera]
    deg = math.degrees(2 * math.atan(PLANE_FACTOR * math.tan(math.radians(c0.fov_x_deg) / 2)))
    if deg > WIDEST:
        return None
    cam = replace(c0, fov_x_deg=deg)
    return deg, basis_renderer(a, render)(replace(scene, cameras={**scene.cameras, a.camera: cam}))


def plane_width(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The camera's field of view from the image plane's full width taken for its half-width, rendered: no free
    parameter."""
    b = inputs.basis
    r = b.extra.get(plane_width.name)
    if r is None:
        return []
    deg, im = r
    change = im.astype(np.float64) - b.base.astype(np.float64)
    text = (f"the camera's field of view {deg:.1f} degrees where the scene says {_num(b.fov_deg)}: the image plane's "
            "full width 2 tan(fov / 2) taken for its half-width")
    return [Candidate("fov", "image plane's full width", text, fit.delta(change), 0, value=deg, change=change)]


plane_width.name, plane_width.prepare = "plane_width", _prepare_plane
