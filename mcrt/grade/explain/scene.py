"""The scene's parameters as families: an overall scale, the light's radiance, each
surface's albedo, and the rendered variations (the light, the objects, the eye, the path depth, the emitter)."""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.basis import AXES, _shift
from mcrt.grade.explain.fit import CAP, Fit, refine
from mcrt.grade.explain.surface_black import black_family, black_words, is_black
from mcrt.grade.feedback import fmt_values as _fmt
from mcrt.grade.feedback import num as _num


def scale(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """An overall scale, and the light's radiance (a scale per channel); other colour mistakes are :mod:`.colour`'s.
    Either scales the render's noise with its mean (a gain: the remainder test allows it)."""
    values = inputs.basis.values
    S, R, w = fit.S, fit.R, fit.w
    ok = fit.ok
    num = np.sum(np.where(ok, S * R * w, 0.0), axis=(0, 1))
    den = np.sum(np.where(ok, R * R * w, 0.0), axis=(0, 1))
    kc = np.where(den > 0, num / np.maximum(den, 1e-300), 1.0)
    k1 = float(np.sum(num) / max(np.sum(den), 1e-300))
    # Near 1, three decimals: "1.005 times", never "1 times".
    factor = f"{k1:.3f}" if abs(k1 - 1) < 0.1 else _num(k1)
    # A constant factor is also what a pixel's sum divided by another count than its samples' gives (samples lost
    # from the sum, a count off): the words name it beside the exposure and the light.
    out = [Candidate("scale", "overall scale", f"the whole image {factor} times the reference (an exposure or "
                     f"display scale, the light's radiance {_fmt(np.asarray(values.get('light_radiance', (1, 1, 1))) * k1, 1)}, "
                     "or each pixel's sum divided by another count than the samples added to it)",
                     fit.model(k1 * R), 1, value=k1, change=(k1 - 1) * R, gain=True)]
    Le = np.asarray(values.get("light_radiance", (1.0, 1.0, 1.0)))
    out.append(Candidate("light_radiance", "the light's radiance",
                         f"the light's radiance {_fmt(Le * kc, 1)} where the scene says {_fmt(Le, 1)} (every channel of "
                         f"the image scaled by {_fmt(kc)})", fit.model(kc * R), 3, value=tuple(Le * kc),
                         change=(kc - 1) * R, gain=True))
    return out


def lagrange(x: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Lagrange weights (len(x), len(nodes)) of the polynomial through ``nodes`` evaluated at ``x``."""
    L = np.ones((len(x), len(nodes)))
    for j, xj in enumerate(nodes):
        for m, xm in enumerate(nodes):
            if m != j:
                L[:, j] *= (x - xm) / (xj - xm)
    return L


def fit_channel(fit: Fit, c: int, xs: np.ndarray, ys: np.ndarray, base: np.ndarray) -> tuple[float, np.ndarray]:
    """The value in [0, 1] (a grid of 101, refined by a parabola) of the polynomial through the renders ``ys``
    (n, H, W) of channel c at ``xs`` that fits best (pixel and tile chi^2), and its change of channel c."""
    grid = np.linspace(0.0, 1.0, 101)
    curves = np.tensordot(lagrange(grid, xs), ys, axes=(1, 0)) - base[None]  # (101, H, W): M - R
    err = np.sum(np.minimum((fit.D[None, :, :, c] - curves) ** 2 * fit.w[None, :, :, c], CAP), axis=(1, 2))
    ct = fit.blocks(np.where(fit.ok[None, :, :, c:c + 1], curves[..., None], 0.0))[..., 0] / fit.cnt[None, :, :, c]
    err = err + np.sum(np.minimum((fit.Dt[None, :, :, c] - ct) ** 2 * fit.wt[None, :, :, c], CAP), axis=(1, 2))
    value = float(refine(grid, err, int(np.argmin(err))))
    return value, np.tensordot(lagrange(np.array([value]), xs), ys, axes=(1, 0))[0] - base


def albedo(fit: Fit, inputs: Inputs) -> list[Candidate]:
    r"""Each surface's albedo, fitted per channel on a grid of 101 values in [0, 1] then refined by a parabola.

    Channel c of the image depends on channel c of the albedos only (RGB
    transport is channel-independent), so the three channels fit apart. A
    fit black in every channel is worded as the surface black, with every
    cause of that (:mod:`.surface_black`).
    """
    b = inputs.basis
    out = []
    seen = _seen(inputs)
    for label, (nodes, imgs, scene_v) in b.albedo.items():
        fitted, dm = [], np.zeros_like(b.base, dtype=np.float64)
        for c in range(3):
            xs = np.append(nodes, scene_v[c])
            ys = np.concatenate([imgs[:, :, :, c], b.base[None, :, :, c]]).astype(np.float64)
            keep = np.concatenate([np.abs(nodes - scene_v[c]) > 1e-3, [True]])
            value, dm[..., c] = fit_channel(fit, c, xs[keep], ys[keep], b.base[..., c])
            fitted.append(value)
        kind = b.values[label][0]
        word = "albedo" if kind == "albedo" else "reflectance"
        hidden = seen is not None and label not in seen
        fam, text = word, (f"{label}{' (not in view)' if hidden else ''} with {word} {_fmt(fitted)} where the scene "
                           f"says {_fmt(scene_v)}")
        # Black in every channel: albedo 0 is one of its causes, not the only one. Out of view too it may be claimed:
        # the whole room's light drops, which no small bias mimics.
        if is_black(fitted):
            fam, text, hidden = black_family(label), black_words(label, scene_v, word), False
        out.append(Candidate(fam, f"{word} of {label}", text, fit.delta(dm), 3, value=tuple(fitted), change=dm,
                             out_of_view=hidden))
    return out


def surface_curve(b, label: str, c: int) -> tuple[np.ndarray, np.ndarray]:
    """The albedo basis's nodes of surface ``label`` in channel c with the scene's own value among them, and the
    renders there less the basis (n, H, W): what the surface's albedo curve interpolates."""
    nodes, imgs, scene_v = b.albedo[label]
    keep = np.concatenate([np.abs(nodes - scene_v[c]) > 1e-3, [True]])
    ys = np.concatenate([imgs[:, :, :, c], b.base[None, :, :, c]]).astype(np.float64)[keep] - b.base[None, :, :, c]
    return np.append(nodes, scene_v[c])[keep], ys


#: A surface's fitted colour counts as changed in :func:`albedos`' words when a channel moves by more than this.
CHANGED = 0.03
#: :func:`albedos` is a candidate only where some surface's colour moves by at least this in a channel: a colour
#: typed, read or clamped wrongly moves by a tenth or more, while a few hundredths on several surfaces is what a
#: change of the light (its samples, its shape) makes too.
TYPED = 0.1
#: Sweeps of :func:`albedos`' coordinate descent over the surfaces.
SWEEPS = 4


def albedos(fit: Fit, inputs: Inputs) -> list[Candidate]:
    r"""Several surfaces' albedos at once: colours typed for the wrong walls, clamped, or read in another order.

    Each surface's effect is its albedo curve of :func:`albedo` (Lagrange
    through its nodes); the model is their sum, which leaves out what two
    changed surfaces do to each other (second order in the changes). The
    fit is a coordinate descent over the surfaces in view (one out of view
    shows only in the light it reflects), channel by channel
    (:data:`SWEEPS` sweeps on the grid of :func:`albedo`, pixel chi^2 with the
    fit's weights), and the candidate's chi^2 is the fit's full criterion.
    Every such surface's three albedos count as parameters, so one surface's
    colour alone is :func:`albedo`'s; the candidate needs two or more
    surfaces changed by more than :data:`CHANGED`, one by :data:`TYPED`, and
    either every one by :data:`TYPED` (colours typed or read from the wrong
    place) or all in one direction (one rule on every colour: a clamp, a
    scale); small changes up on some surfaces and down on others are what a
    mistake in how light bounces makes (it moves light between surfaces),
    which colours typed wrongly seldom are. It is flexible
    (:attr:`~mcrt.grade.candidates.Candidate.flexible`): claimed only where
    its remainder is noise and no other candidate's is.
    """
    b = inputs.basis
    seen = _seen(inputs)
    # A surface out of view shows only in the light it reflects, which every surface's colour changes alike.
    labels = [lab for lab in b.albedo if seen is None or lab in seen]
    if len(labels) < 2:
        return []
    grid = np.linspace(0.0, 1.0, 101)
    w = np.where(fit.ok, fit.w, 0.0)
    fitted = {lab: list(b.albedo[lab][2]) for lab in labels}
    dm = np.zeros_like(b.base, dtype=np.float64)
    for c in range(3):
        polys = {}
        for lab in labels:
            xs, ys = surface_curve(b, lab, c)
            gram = np.einsum("jhw,khw,hw->jk", ys, ys, w[..., c])
            polys[lab] = (xs, ys, gram, lagrange(grid, xs))
        part = {lab: np.zeros(b.base.shape[:2]) for lab in labels}
        for _ in range(SWEEPS):
            for lab in labels:
                xs, ys, gram, L = polys[lab]
                r = fit.D[..., c] - (sum(part.values()) - part[lab])
                err = -2 * L @ np.einsum("jhw,hw->j", ys, r * w[..., c]) + np.einsum("gj,jk,gk->g", L, gram, L)
                i = int(np.argmin(err))
                a = float(refine(grid, err, i))
                fitted[lab][c] = a
                part[lab] = np.tensordot(lagrange(np.array([a]), xs), ys, axes=(1, 0))[0]
        dm[..., c] = sum(part.values())
    moved = {lab: max(abs(x - y) for x, y in zip(fitted[lab], b.albedo[lab][2])) for lab in labels}
    changed = [lab for lab in labels if moved[lab] > CHANGED]
    if len(changed) < 2 or max(moved.values()) < TYPED:
        return []
    ways = {np.sign(np.mean(np.subtract(fitted[lab], b.albedo[lab][2]))) for lab in changed}
    if len(ways) > 1 and min(moved[lab] for lab in changed) < TYPED:
        return []  # a few hundredths up here and down there: light moved between surfaces, not colours typed
    black = _black_in_hand_in(fit, inputs, changed)
    words = "; ".join(f"{lab} {_fmt(fitted[lab])} where the scene says {_fmt(b.albedo[lab][2])}"
                      for lab in changed if lab not in black)
    text = f"the colours of {len(changed)} surfaces other than the scene's: {words}"
    if black:  # black in the hand-in: every cause of that named, a face missing among them
        them = "them" if len(black) > 1 else "it"
        text = (f"{' and '.join(black)} black (missing from the scene, as nothing lies behind {them} in the closed "
                f"room; or with albedo 0; or with normals facing away, so that one-sided shading (max(0, n.l)) gives "
                f"0: check the list of surfaces, the triangles' winding, each normal's direction)"
                + (f", and the colours of other surfaces: {words}" if words else ""))
    fam = black_family(black[0]) if black else "albedo"
    return [Candidate(fam, "albedos of several surfaces", text, fit.delta(dm), 3 * len(labels),
                      value={lab: tuple(fitted[lab]) for lab in changed}, change=dm, flexible=True)]


#: A surface is black in the hand-in where at least this share of its pixels are holes (0 where the light reaches).
HOLED = 0.5


def _black_in_hand_in(fit: Fit, inputs: Inputs, labels: list[str]) -> list[str]:
    """Those of ``labels`` (the albedo basis's: 'wall BC') the hand-in shows black: :data:`HOLED` of the surface's
    pixels 0 in every channel where the light reaches it (:func:`mcrt.grade.explain.pixels.black_holes`). The fit of
    several surfaces at once leaves a black surface's colour loosely fixed (the others' changes reach its pixels
    too: a wall fitted (0.02, 0.01, 0.08) predicts it black), so the hand-in says it: black, with every cause of
    that (:mod:`.surface_black`), a wall missing among them."""
    from mcrt.grade.explain.pixels import black_holes
    from mcrt.grade.explain.pixels import directly_lit

    if inputs.labels is None:
        return []
    holes = black_holes(fit.S, fit.R, fit.ok.all(axis=-1), directly_lit(inputs.basis))
    if holes is None:
        return []
    names = np.array([n.split(" (")[0] for n in inputs.label_names])[inputs.labels]
    return [lab for lab in labels if (names == lab).any() and float(np.mean(holes[names == lab])) >= HOLED]


def _seen(inputs: Inputs) -> set[str] | None:
    """The albedo basis's labels of the surfaces some pixel sees directly ('wall DE', 'the floor'); None without
    labels."""
    if inputs.labels is None:
        return None
    names = [inputs.label_names[i] for i in np.unique(inputs.labels)]
    return {n.split(" (")[0] for n in names}


def rendered(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """The rendered variations: the best node of each family (light, objects, eye, depth)."""
    b = inputs.basis
    out = []
    v = b.values
    best_moved: dict[str, Candidate] = {}
    for key, nodes in b.nodes.items():
        if key == "eye_back":
            out.append(_looking_back(fit, b.base, nodes[0][1]))
            continue
        if key == "eye_turned":
            out.append(_turned_quarter(fit, b.base, nodes, v))
            continue
        scores = [fit.delta(img.astype(np.float64) - b.base) for _, img in nodes]
        i = int(np.argmin(scores))
        val, img = nodes[i]
        dm = img.astype(np.float64) - b.base
        cand = _node_candidate(key, val, scores[i], v, b.max_depth)
        if cand is None:
            continue
        fam = key.split(":")[0]
        cand.change = dm
        if fam in ("moved", "swapped", "origin"):  # one placement of each object: the best
            name = key.split(":")[1]
            if name not in best_moved or cand.chi2 < best_moved[name].chi2:
                best_moved[name] = cand
            continue
        out.append(cand)
    out += list(best_moved.values())
    emit = dict(b.nodes.get("depth", []))
    if 1 in emit:
        dm = -emit[1].astype(np.float64)
        out.append(Candidate("emitter_hidden", "the light not seen directly", "the light itself black where the camera "
                             "sees it directly (emission left out at the first hit)", fit.delta(dm), 0, change=dm))
        out += _emitter_seen(fit, emit[1].astype(np.float64), v.get("light_radiance", (1.0, 1.0, 1.0)))
    return out


def _missing_words(name: str, v: dict) -> str:
    """What an object (or every object: ``name`` 'objects') missing from the image says, ``v`` the basis's values."""
    if name == "objects":
        every = " and ".join(f"the {o}" for o in v.get("objects", ()))
        return (f"every object ({every}) missing from the image: never added to the scene's list, or the intersection "
                "loop returning the first shape a ray meets in the list (the room's before the objects) rather than the "
                "nearest")
    # A mirror that passes rays on unchanged (its reflected direction computed, not used) is missing from the image
    # as far as the image can tell: its shadow is soft and small beside it. An object placed outside the room by its
    # transform (a translation scaled, matrices multiplied in the other order) is missing from the image as well:
    # the words send the student to both.
    through = (", or rays passing through it unchanged (a mirror's reflected direction computed but never used)"
               if f"the mirror {name}" in v else "")
    return (f"the {name} missing from the image (never added to the scene, or placed out of sight by its transform: a "
            f"translation scaled, the matrices multiplied in the other order){through}")


def _node_candidate(key: str, val, chi2: float, v: dict, max_depth: int) -> Candidate | None:
    """The candidate of one rendered variation (a basis node's key and value, its chi^2), in words; None for a key
    no family words."""
    fam = key.split(":")[0]
    if key.startswith("light_") and key not in ("light_size", "light_sign", "light_swapped"):
        axis = AXES.index(key[-1])
        c = _shift(v["light_center"], axis, val)
        text = (f"the light moved by {val:+g} along {key[-1]} (centre {_fmt(c, 2)} where the scene says "
                f"{_fmt(v['light_center'], 2)})")
        cand = Candidate("light_position", f"light moved along {key[-1]}", text, chi2, 1, value=c)
    elif key == "light_sign":
        c = tuple(-x if k == val else x for k, x in enumerate(v["light_center"]))
        cand = Candidate("light_position", "the light's coordinate's sign", f"the light's {AXES[val]} typed with "
                         f"the wrong sign (centre {_fmt(c, 2)} where the scene says {_fmt(v['light_center'], 2)})",
                         chi2, 0, value=c)
    elif key == "light_swapped":
        c = tuple(v["light_center"][i] for i in val)
        cand = Candidate("light_position", "the light's x and y swapped", f"the light's centre read (y, x): "
                         f"{_fmt(c, 2)} where the scene says {_fmt(v['light_center'], 2)}", chi2, 0, value=c)
    elif key == "light_size":
        s = tuple(x * f for x, f in zip(v["light_size"], val))  # val: the factors of its two sides
        cand = Candidate("light_size", "the light's size", f"the light's size {_num(s[0])} x {_num(s[1])} where "
                         f"the scene says {_num(v['light_size'][0])} x {_num(v['light_size'][1])} (same radiance)",
                         chi2, 1, value=s)
    elif fam == "missing":
        name = key.split(":")[1]
        what = _missing_words(name, v)
        cand = Candidate("object_missing", f"{name} missing", what, chi2, 0, value=name)
    elif fam == "moved":
        name, ax = key.split(":")[1:]
        cand = Candidate("object_moved", f"{name} moved", f"the {name} moved by {val:+g} along {ax}", chi2, 1,
                         value=(name, ax, val))
    elif key == "swapped:room":
        cand = Candidate("object_moved", "the room's corners swapped", "the room's corners read (y, x): the room "
                         "mirrored about the line x = y, the light and the objects where the scene puts them", chi2, 0,
                         value=("room", "yx"))
    elif fam == "swapped":
        name = key.split(":")[1]
        order = "(" + ", ".join(AXES[i] for i in val) + ")"
        cand = Candidate("object_moved", f"{name}'s axes swapped", f"the {name}'s coordinates read in the order "
                         f"{order} (x, y and z mixed up, as a program written for y up does)", chi2, 0,
                         value=(name, order))
    elif fam == "plane":
        name = key.split(":")[1]
        z = v[name] + val
        cand = Candidate("object_moved", f"the {name}'s height", f"the {name} at z = {_num(z)} where the scene says "
                         f"{_num(v[name])}", chi2, 1, value=(name, z))
    elif fam == "origin":
        name = key.split(":")[1]
        cand = Candidate("object_moved", f"{name} at the origin", f"the {name} about the origin (its coordinates "
                         "taken in model space: its placement in the room never applied)", chi2, 0,
                         value=(name, "origin"))
    elif key == "eye_axis":
        what = "-z, x right and y up: OpenGL's convention" if val[2] < 0 else "+z, with y up"
        cand = Candidate("rotation", "the camera's rays in camera space", f"the camera's rays built in camera space and "
                         f"never turned into the world's frame (looking along the world's {what}), where the scene's "
                         f"camera looks along {_fmt(v['forward'], 2)}", chi2, 1, value=val)
    elif key.startswith("eye_"):
        cand = Candidate("eye", "the camera's eye", f"the camera's eye moved by {val:+g} along {key[-1]} (at "
                         f"{_fmt(_shift(v['eye'], AXES.index(key[-1]), val), 2)} where the scene says "
                         f"{_fmt(v['eye'], 2)})", chi2, 1, value=val)
    elif key == "depth":
        # A path cut at a depth and a path whose weight is lost there give one image: the words name both.
        lost = "" if val == -1 or (max_depth != -1 and val > max_depth) else (
            ", or each path's light past that depth lost (Russian roulette from there that ends every path or divides "
            "by a survival probability far above 1, or a throughput that becomes 0)")
        cand = Candidate("depth", "path depth", f"paths cut at depth {'unbounded' if val == -1 else val} "
                         f"(Mitsuba's convention, where the assignment asks for {max_depth}){lost}", chi2, 1,
                         value=val)
    else:
        return None
    return cand


def _looking_back(fit: Fit, base: np.ndarray, back: np.ndarray) -> Candidate:
    """The camera looking the opposite way: its render, as it is or mirrored left to right (a right vector that did
    not flip with the forward one), whichever fits better."""
    best = None
    for mirrored, img in ((False, back), (True, back[:, ::-1])):
        dm = img.astype(np.float64) - base
        chi = fit.delta(dm)
        if best is None or chi < best[0]:
            best = (chi, mirrored, dm)
    chi, mirrored, dm = best
    return Candidate("rotation", "the camera looking back", "the camera looking the opposite way (its forward vector's "
                     "sign flipped, so the image shows the room behind it" + (", mirrored left to right)" if mirrored
                                                                            else ")"),
                     chi, 0, value="back", change=dm)


def _turned_quarter(fit: Fit, base: np.ndarray, nodes, v: dict) -> Candidate:
    """The camera turned a quarter to the left or right: the better of the two renders (one parameter, the side)."""
    from mcrt.grade.explain.basis import _turned

    chi, side, dm = min(((fit.delta(img.astype(np.float64) - base), side, img.astype(np.float64) - base)
                         for side, img in nodes), key=lambda t: t[0])
    f = _turned(v["forward"], v["up"], 1.0 if side == "left" else -1.0)
    return Candidate("rotation", "the camera turned a quarter", f"the camera turned 90 degrees to the {side} (looking "
                     f"along {_fmt(f, 2)} where the scene says {_fmt(v['forward'], 2)}): its forward vector's "
                     "horizontal components exchanged, as a yaw from atan2 with its arguments swapped, or x and y "
                     "mixed up, makes it", chi, 1, value=side, change=dm)


#: Relative spread of the per-channel factors of the light seen within which one factor is fitted for all three.
GREY_SEEN = 0.02


def _emitter_seen(fit: Fit, E: np.ndarray, Le) -> list[Candidate]:
    """The light seen directly at k times its radiance, its light on the surfaces right (the emission at the first
    hit weighted, as by an MIS weight where no light sample competes, or clamped to 1 where the camera sees it, or
    tinted, as a debug colour for the rays that meet the light): change (k - 1) E, E the image of paths cut at depth
    1, k by weighted least squares, one per channel where they differ by more than :data:`GREY_SEEN` (three
    parameters). None near k = 0 (the light black: ``emitter_hidden``) or k = 1."""
    w = np.where(fit.ok, fit.w, 0.0)
    den = np.sum(w * E * E, axis=(0, 1))
    if not np.all(den > 0):
        return []
    ks = 1.0 + np.sum(w * fit.D * E, axis=(0, 1)) / den
    grey = float(np.max(ks) - np.min(ks)) <= GREY_SEEN * max(float(np.mean(ks)), 1e-9)
    if grey:
        k = 1.0 + float(np.sum(w * fit.D * E)) / float(np.sum(den))
        ks = np.full(3, k)
    # Down to 1/20 of the radiance of 20 (the light seen clamped to 1, so as not to blow out the image).
    if np.all(ks < 0.02) or np.all(np.abs(ks - 1.0) < 0.02) or np.any(ks < 0.0):
        return []
    dm = (ks - 1.0) * E
    Le = np.asarray(Le, np.float64)
    # Seen at about 1: the emission clamped to the display's white where the camera sees it.
    clamped = ", or clamped to 1 where the camera sees it" if abs(float(np.max(Le * ks)) - 1.0) < 0.05 else ""
    factor = f"{_num(ks[0])} times as bright" if grey else f"with its colour times {_fmt(ks, 2)}"
    tint = "" if grey else ", or tinted there (a debug colour for the rays that meet the light)"
    return [Candidate("emitter_seen", "the light seen at a factor", f"the light itself {factor} where the camera sees "
                      f"it directly ({_fmt(Le * ks, 1)} where the scene says {_fmt(Le, 1)}), its light on the surfaces "
                      f"right (the emission at the first hit weighted, as by an MIS weight there{clamped}{tint})",
                      fit.delta(dm), 1 if grey else 3, value=float(ks[0]) if grey else tuple(float(x) for x in ks),
                      change=dm, generalises=("emitter_hidden",),
                      # A curve on the values that changes mostly the light's own value reads the same image.
                      rivals=("tone_curve",))]


scale.name, albedo.name, rendered.name = "scale", "albedo", "rendered"
