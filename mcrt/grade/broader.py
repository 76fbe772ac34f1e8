r"""What a partial reading and its remainder point to together: a broader cause, said where both agree.

A partial reading ("partly like X, which explains 59 %; something else is
wrong on ...") names no cause: X leaves structure. Two kinds of X, though,
tell on their own which part of the program is wrong even where the exact
change is none the families render:

* **an object's geometry** (:data:`GEOMETRY`: the tetrahedron or the sphere
  resized, moved or missing) that explains at least
  :data:`mcrt.grade.adequacy.PARTIAL_LEAD` of the difference: most of what
  differs is that object's outline, its shadow and its reflections, so its
  shape, size or place is wrong, in a way one scale or one shift does not
  capture (a vertex elsewhere, a face missing, an ellipsoid), where what is
  left lies beside the object too (its outline's other side, its shadow,
  what it hides): on the object's own pixels alone it could as well be its
  material (a mirror's reflections changed, a surface shaded otherwise). The
  words send the student to that object's vertices, transform and
  intersection, without claiming which;
* **black pixels on the room's surfaces with the rest of the room darker**
  (:func:`room_faces`): black pixels alone are pixels never written or NaN
  samples, and the room around them is then as rendered. If the camera
  sees the void through faces missing from the room, light escapes through
  them too, and every other surface is darker, by one factor roughly: the
  remainder's least-squares fit :math:`r = -k R` off the black pixels,
  weighted by the noise (a firefly's pixel counts little, no pixel beyond
  a relative error of :data:`mcrt.grade.candidates.FLOOR`, the light's own
  pixels left out), must give :math:`k \ge` :data:`MIN_LOSS` at
  :data:`LOSS_Z` standard errors. Black pixels that are the reference's
  brightest (:data:`BRIGHTEST`) are codes overflowing, not holes. Both
  together point to the faces. Where another reading leads (a wall's colour
  darkened, fitted as close as it gets), the black pixels are the hand-in's
  where the light reaches (:func:`mcrt.grade.explain.pixels.black_holes`), which
  that reading leaves lit, none of them on the light itself;
* **the diffuse bounce** (:data:`BOUNCE`: a bounce drawn or weighted wrongly,
  :mod:`mcrt.grade.explain.bounce`, or the catalogue's samplers that are
  not cosine-distributed) leading, where nothing is left on the light's own
  pixels: only the bounce's directions or their weight move light between
  the room's surfaces that way, and the light seen directly is the one
  thing a bounce cannot change. The mistakes the families render are a few
  of the many ways to draw a direction (a disk's radius, a frame's axes, a
  random vector's range), and a path's weight after the bounce (Russian
  roulette's survival divided wrongly) changes the bounced light alike; the
  words send the student to the sampling of the bounce, its weight and
  roulette's, without claiming which;
* **where the light's samples come from** (:data:`LIGHT_REGION`: the light
  sampled on a quarter of itself, about another centre, over another
  square or rectangle of its plane, :mod:`mcrt.grade.explain.light_sampling`)
  leading, where nothing is left on the light's own pixels nor the light
  seen larger (:func:`light_seen_larger`): the light on
  surfaces then comes from points other than the light's own, and the
  light seen directly, which no light sample makes, is right. The families
  render uniform rectangles; a triangle of the light, a parallelogram, a
  sampler crowding its points or a clamped range are others, which the
  words name together (the sample point's code and its pdf), claiming none;
* **a filter after rendering** (:data:`FILTERS`): a filter's fit (a blur, a
  binomial or box kernel, a rank filter) leading on an image whose noise
  itself shows a filter (the structure check's correlation between
  neighbouring pixels or its reduced variance: ``Scene2D.filtered``), which
  no render mistake makes: the filter's kernel or its edges are another
  than the families try (a Wiener or edge-preserving filter, a kernel of
  other weights), and the words name a filter without claiming which;
* **the view** (:func:`view_lead`): a change of the camera (its field of
  view, eye, turn, projection or aspect) or a window of the render enlarged
  leading on an image whose edges the registration test found displaced
  against the reference's (``Scene2D.misregistered``): the view is not the
  scene's camera's, in a way none of the changes tried captures (a
  look-at's basis, a projection of its own, a viewport of another size),
  which the words name together with a crop or resize after rendering;
* **one object's own pixels** (:func:`surface_object`): a lead that acts
  on one of :data:`OBJECTS` (at least :data:`ON_OBJECT` of its change, by
  the noise's weights, on its pixels) with a remainder on that object's
  pixels alone. Nothing around the object changed (its shadow, its outline's
  other side), so what differs is how the object itself looks: for the
  mirror sphere, the directions it reflects (the reflection's code, the
  sphere's normal, or a shape that is not the sphere: facets, a squashed
  or partial mesh) or what its reflected rays gather (the path after the
  mirror bounce: its depth, its specular flag, the light it counts next:
  :data:`SPHERE_WORDS`); for the tetrahedron,
  its shading (its material, normals, a second material mixed in) or its
  faces. The image cannot tell these apart, and the words say so.

None changes the verdict (PARTIAL) or the points; only the words and
the causes they name (``Explanation.broader``).

Where no lead fits that way, or no candidate leads at all (nothing we tried
explains most of the difference), one more reading is tried
(:func:`bounced_light`): **the bounced light alone changed**. An image is
the light each surface receives straight from the lamp (the paths cut after
their light sample at the first surface: the basis render of depth 2, with
its shadows and the light seen) plus the light that bounced off other
surfaces first. A mistake after a path's first surface (the bounce's
direction, its frame, pdf or weight, Russian roulette, where the path ends)
changes only the second, smoothly over each surface, as the bounced light
is an integral over the hemisphere. So the difference is fitted three ways,
each a polynomial factor of degree :data:`SMOOTH_ORDER` in the pixel's place,
one per surface and channel (:func:`smooth_fit`): on the bounced light, on
the direct light, and on the whole image. The reading holds where the
first leaves only noise (the remainder test), the second does not, and the
first fits better than both others by
:data:`mcrt.grade.adequacy.CONFIRM_Z` (:func:`mcrt.grade.adequacy.closeness`
without the BIC's credit: the three have as many parameters): the
shadows' edges, which only the direct light has, tell the two apart. And
the direct light must be right: a constant factor on each surface's direct
light, fitted beside the bounced light's, differs from 1 on none (its
z-scores, Bonferroni's bound at the bias test's level), the light's own
pixels, which are direct light alone, among them. The
mirror's pixels are left out: they show the room's bounced light sharp,
which no smooth factor on the sphere describes. The words send the student
to the steps after a path's first surface, naming none.

Where that does not hold, its mirror image is tried (:func:`direct_light`):
**the first surface's direct light alone changed**. A program that
computes the light a camera ray's first surface receives straight from the
lamp in a step of its own (its own light sample, pdf, cosines, fall-off or
shadow ray), and the rest of the path otherwise, changes only that part:
the basis render of depth 2 less that of depth 1 (the light seen
directly). The same three fits, on that part, on the rest (the light seen
and the bounced light) and on the whole image, with the same conditions
(:func:`_part_changed`): the part's fit leaves only noise, the rest's does
not, the part's fits better than both by
:data:`mcrt.grade.adequacy.CONFIRM_Z`, and the rest needs no factor of its
own on any surface, the light's own pixels among them. An albedo wrong
everywhere scales a surface's direct and bounced light alike and is not
read so; a light sample wrong at every vertex changes the bounced light too
and is not read so either. The words send the student to the light sample
at the first surface, naming none of its steps.

Where neither holds, one last reading asks where the difference lies
(:func:`sphere_alone`): **on the mirror sphere's own pixels alone**, the
rest of the image consistent with noise once they are left out (and no
other surface's pixels so), with no filter, displaced edge or lead that
changes the image as a whole (:data:`IMAGE_WIDE`: such a change is
largest where the detail is finest, the mirror's). Nothing the sphere
shadows or lights changed, so what differs is the sphere itself or what it
shows: the words name its reflection, its normal, its shape, size and
place, and the path after a mirror bounce (:data:`SPHERE_WORDS`) together,
claiming none.

A description has one broader reading of its own (:func:`after_rendering`):
a monotone curve on the values (DESCRIBED: any curve, none of the common
ones) that changes **the light seen directly and the room**, and the light
by another factor than the room. The light's own pixels show its radiance
as the scene gives it, which no mistake in a path's weights, depth or
surfaces changes; a mistake in the light's radiance changes it with the
room by one factor (a scale, the exposure's reading). A curve that changes
both otherwise was applied to the values after they were rendered (to each
pixel, or to each sample before the mean): the words send the student to
the steps between the render and the file, none of which the common curves
match.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import norm

from mcrt.grade.candidates import FLOOR
from mcrt.stats import LUMINANCE_WEIGHTS

#: The families of a lead that changes the image as a whole, not the scene (a filter, a resampling, a sharpening,
#: the view, the pixels' places): such a change is largest where the image's detail is finest, which is the mirror's,
#: so a difference on the mirror alone beside it is no evidence of the sphere (:func:`sphere_alone`).
IMAGE_WIDE = ("blur", "resampling", "sharpen", "pixel_offset", "fov", "eye", "rotation", "aspect", "camera_model")
#: What the mirror sphere's pixels alone can say, in words (:func:`reading`'s one object's own pixels, and
#: :func:`sphere_alone`): the sphere itself, or the paths it reflects, which the image cannot tell apart.
SPHERE_WORDS = ("the direction it reflects and its weight (the reflection's code, a cosine or a colour in it), the "
                "normal at its hit point, its shape, size or place (a sphere a little smaller, flattened, faceted or "
                "sunk shows the room otherwise), or how a path goes on after the mirror bounce (the depth it has left, "
                "the flag that says its last bounce was specular, the light it counts at the next surface: twice or "
                "not at all): check the mirror's reflect and its weight, the sphere's normal, how the sphere is built "
                "and intersected, and the path's state after a mirror bounce")
#: An object's geometry wrong, in words: what it means, and where to look.
GEOMETRY_WORDS = ("its shape, size or place is not the scene's in a way one scale or one shift does not capture (check "
                  "its vertices or centre and radius, its transform and its ray intersection test)")
#: The families whose fit moves, resizes or removes one object (value: the object's name).
GEOMETRY = ("object_size", "object_moved", "object_missing")
#: The families whose fit draws or weights the diffuse bounce otherwise than cosine-weighted: (family, name) with
#: name None for every candidate of the family (mcrt.grade.explain.bounce) or a catalogue mutant's name.
BOUNCE = (("bounce", None), ("catalogue", "ball_plus_normal"), ("catalogue", "uniform_as_cosine"))
#: The light-sampling candidates (mcrt.grade.explain.light_sampling, by name) that draw the light's samples from
#: points other than the light's own (not its weight alone: a factor on the light's samples is also a BRDF's or
#: an emitter's constant).
LIGHT_REGION = ("light sampled on a quarter", "light sampled elsewhere", "light sampled over a rectangle")
#: The families whose fit filters the finished image (mcrt.grade.explain.curves): with the noise showing a filter, a
#: partial reading led by one points to a filter of another kernel.
FILTERS = ("blur",)
#: The families whose fit changes the view (mcrt.grade.explain.camera): with the edges displaced, a partial reading
#: led by one, or by a window of the render enlarged (:func:`view_lead`), points to the view.
VIEW = ("fov", "eye", "rotation", "aspect", "camera_model")
#: Least share of a lead's change (its square, weighted by the noise) on one object for it to act on that object.
ON_OBJECT = 0.5
#: The objects (scene names) whose geometry a program builds itself: the room's surfaces have families of their own.
OBJECTS = ("tetrahedron", "sphere")
#: Least relative darkening of the room off the black pixels for the light to be escaping through holes.
MIN_LOSS = 0.005
#: ... and its least size in standard errors of that darkening (its weighted least-squares fit's).
LOSS_Z = 4.0
#: Least size, in standard errors, of the light's change and of the curve's gain on the room for a curve to have
#: changed both (:func:`after_rendering`) ...
CURVE_Z = 5.0
#: ... and the least relative change of the light's value, and of its factor against the room's.
LIGHT_EFFECT = 0.05
#: Degree of the polynomial in the pixel's place, per surface and channel, that a smooth factor on a part of the
#: image is (:func:`smooth_fit`).
SMOOTH_ORDER = 2
#: Share of the black pixels that must lie on the room's walls, floor and ceiling.
ON_ROOM = 0.9
#: Black pixels (nearly) all above this quantile of the reference's luminance are its brightest values: codes that
#: overflow (a value past the top of the file's range written 0) blacken those, holes any.
BRIGHTEST = 0.75
#: The pixels touching the light's are this many times the reference's there where the light is seen larger
#: (:func:`light_seen_larger`): a light sample's region leaves them as the reference's, up to noise.
LARGER = 2.0

_LUM = np.asarray(LUMINANCE_WEIGHTS)


def reading(lead, remainder: np.ndarray, R: np.ndarray, mask: np.ndarray, var: np.ndarray, labels: np.ndarray,
            names, objects, *, holes: np.ndarray | None = None, filtered: bool = False,
            misregistered: bool = False) -> tuple[str, str] | None:
    """(family, words) of the broader cause of partial reading ``lead`` (its remainder ``remainder``, (H, W, 3);
    ``var`` the noise's variance per pixel; ``labels`` and ``names`` the surfaces; ``objects`` the labels the
    remainder was found on; ``holes`` the hand-in's black pixels where the light reaches,
    :func:`mcrt.grade.explain.pixels.black_holes`; ``filtered`` whether the image's noise shows a filter,
    ``misregistered`` whether its edges are displaced), or None."""
    obj = geometry_object(lead)
    # The object's own pixels cannot tell its shape from its material (a mirror's reflections, a surface's shading):
    # only a remainder on what lies around it (its outline's other side, its shadow) points to its geometry.
    if obj is not None and any(obj not in names[k] for k in objects):
        return ("object_geometry", f"together they point to the {obj}'s geometry: {GEOMETRY_WORDS}")
    loss = room_faces(lead, remainder, R, mask, var, labels, names, holes=holes)
    if loss is not None:
        return ("room_faces", "together they point to faces missing from the room: the black pixels are the void "
                f"seen through them, and the rest of the room is darker by {100 * loss:.1f} % as light escapes "
                "through them (check how the walls', the floor's and the ceiling's polygons are split into "
                "triangles, and which of those are built)")
    if _is_bounce(lead) and not any(names[k] == "the light" for k in objects):
        return ("diffuse_bounce", "together they point to the diffuse bounce: the directions a path goes on in "
                "from a diffuse surface are not cosine-distributed, or not weighted by f cos / pdf for the pdf they "
                "were drawn from, or the weight a path carries on after it is off, in a way none of the mistakes we "
                "render captures exactly (check how the direction is drawn, the frame that turns it about the normal, "
                "its weight, and Russian roulette's survival probability and the division by it)")
    if lead is not None and lead.family == "light_sampling" and lead.name in LIGHT_REGION and \
            not any(names[k] == "the light" for k in objects) and not light_seen_larger(remainder, R, labels, names):
        return ("light_region", "together they point to where the light's samples are drawn: the light on surfaces "
                "comes from points other than the light's own, or spread otherwise over it, or weighted by another "
                "pdf than theirs, in a way none of the mistakes we render captures exactly, the light itself seen "
                "right (check how a sample point is drawn on the light: its corner, its sides, its random numbers' "
                "range, and the pdf it is divided by)")
    if filtered and lead is not None and lead.family in FILTERS:
        return ("filtered", "together with the noise, which is correlated between neighbouring pixels or reduced as a "
                "filter reduces it, they point to a filter applied after rendering with another kernel than those we "
                "try (a blur, a denoiser, a rank filter such as a median or maximum, or an edge-preserving one: check "
                "each step between the render and the file that mixes neighbouring pixels)")
    if misregistered and view_lead(lead):
        return ("view", "together with the edges, which the registration test finds displaced against the "
                "reference's, they point to the view: the camera's rays do not start or point where the scene's "
                "camera's do, in a way none of the changes we try captures (check the eye, the look-at basis and its "
                "up vector, the field of view and how a pixel's coordinates become a direction), or the image was "
                "cropped or resized from a render of another size (a viewport or canvas size left at a default)")
    obj = surface_object(lead, R, var, mask, labels, names, objects)
    if obj == "sphere":
        return ("sphere_surface", f"together they point to what the mirror sphere shows, with nothing around it "
                f"changed: {SPHERE_WORDS}")
    if obj is not None:
        return ("object_surface", f"together they point to how the {obj} itself looks, with nothing around it "
                f"changed: its material or shading (its colour, its normals, a second material mixed in) or its "
                f"faces (check the {obj}'s material, its normals and the faces its mesh is built from)")
    return None


def light_seen_larger(remainder: np.ndarray, R: np.ndarray, labels: np.ndarray, names) -> bool:
    """Whether the light the camera sees is larger than the scene's: the pixels touching the light's own (the
    ceiling's, which its outline crosses) are, in the median, more than LARGER times the reference there. Their
    remainder is the light seen where the ceiling should be, which no light sample makes."""
    from scipy import ndimage

    if "the light" not in names:
        return False
    light = labels == names.index("the light")
    ring = ndimage.binary_dilation(light) & ~light
    ref = R[ring] @ _LUM
    ok = ref > 0
    if np.count_nonzero(ok) < 4:
        return False
    return float(np.median((remainder[ring] @ _LUM)[ok] / ref[ok])) > LARGER - 1.0


def surface_object(lead, R, var, mask, labels, names, objects) -> str | None:
    """The one of :data:`OBJECTS` whose own pixels hold the whole remainder (``objects``, labels) and at least
    :data:`ON_OBJECT` of ``lead``'s change, weighted by the noise (module docstring); else None."""
    if lead is None or lead.change is None or not objects:
        return None
    found = {next((o for o in OBJECTS if o in names[k]), None) for k in objects}
    if len(found) != 1 or None in found:
        return None
    obj = found.pop()
    on = np.zeros(mask.shape, bool)
    for k, n in enumerate(names):
        if obj in n:
            on |= labels == k
    v = var + (FLOOR * R) ** 2
    e = np.where(mask[..., None], lead.change**2 / np.maximum(v, 1e-30), 0.0).sum(axis=-1)
    total = float(e.sum())
    return obj if total > 0 and float(e[on].sum()) >= ON_OBJECT * total else None


def view_lead(lead) -> bool:
    """Whether ``lead`` changes the view: a camera family's (:data:`VIEW`) or a window of the render enlarged."""
    return lead is not None and (lead.family in VIEW
                                 or (lead.family == "resampling" and lead.name == "window enlarged"))


def _is_bounce(lead) -> bool:
    """Whether ``lead`` draws or weights the diffuse bounce wrongly (:data:`BOUNCE`)."""
    return lead is not None and any(lead.family == f and (n is None or lead.name == n) for f, n in BOUNCE)


def geometry_object(lead) -> str | None:
    """The object whose size, place or presence ``lead`` fits, where it is one of :data:`OBJECTS`; else None."""
    if lead is None or lead.family not in GEOMETRY:
        return None
    v = lead.value
    name = v.get("object") if isinstance(v, dict) else v[0] if isinstance(v, (tuple, list)) else v
    return name if name in OBJECTS else None


def room_faces(lead, remainder, R, mask, var, labels, names, *, holes=None) -> float | None:
    """The room's relative darkening off the black pixels, where they lie on its walls, floor and ceiling
    (:data:`ON_ROOM`; not where the light is hidden, which is another reading) and the darkening is significant
    (module docstring); else None. The black pixels are ``lead``'s where it is the black pixels' reading, else the
    ``holes`` (the hand-in's black pixels where the light reaches, none on the light itself: the void seen through
    the room is never the light) whatever the lead: a lead that lights them (a wall's colour darkened, the light's
    samples moved) leaves them, and the room around them says whether light escapes there."""
    if lead is None or lead.change is None:
        return None
    if lead.family == "bad_pixels" and lead.name == "black pixels":
        if not isinstance(lead.value, dict) or lead.value.get("in_shadow"):  # black where the light is hidden: the bounced light lost, another reading
            return None
        bad = np.any(lead.change != 0.0, axis=-1) & mask
    elif holes is not None and not any(names[k] == "the light" for k in np.unique(labels[holes & mask])):
        bad = holes & mask
    else:
        return None
    room = np.array([n.startswith("wall ") or n in ("the floor", "the ceiling") for n in names])
    if not bad.any() or float(np.mean(room[np.minimum(labels[bad], len(names) - 1)])) < ON_ROOM:
        return None
    lum = R @ _LUM
    if float(np.mean(lum[bad] > np.quantile(lum[mask], BRIGHTEST))) >= ON_ROOM:
        return None  # the brightest values black: codes overflowing, not holes
    off = mask & ~bad & (R @ _LUM < 1.0)  # the light's own pixels get no light from the room
    r, ref = (remainder + lead.change)[off] @ _LUM, R[off] @ _LUM  # the hand-in's difference there, whatever the lead
    v = var[off] @ _LUM**2 + (FLOOR * ref) ** 2  # no pixel's weight beyond a relative error of FLOOR
    info = float(np.sum(ref * ref / v))  # the least-squares fit of r = -k R, weighted by the noise: k's information
    if info <= 0:
        return None
    loss = -float(np.sum(ref * r / v)) / info
    return loss if loss >= MIN_LOSS and loss * np.sqrt(info) >= LOSS_Z else None


def after_rendering(lead, S: np.ndarray, R: np.ndarray, mask: np.ndarray, var: np.ndarray, labels: np.ndarray,
                    names) -> tuple[str, str] | None:
    """("value_curve", words) where description ``lead`` (a curve on the values) changes the light seen directly
    and the room, the light by another factor than the room (module docstring); else None. ``var`` is the noise's
    variance per pixel, (H, W, 3)."""
    from mcrt.grade.feedback import flat_level, fmt_values

    # One value everywhere is no view of the scene: a camera that sees one surface, or every pixel given one value.
    if lead is None or lead.change is None or not lead.describes or flat_level(lead.value) is not None:
        return None
    k = next((k for k, n in enumerate(names) if n == "the light"), None)
    if k is None:
        return None
    light = mask & (labels == k)
    room = mask & (labels != k) & (R @ _LUM < 1.0)  # the light's reflections (in the mirror) are the light's too
    if light.sum() < 4 or room.sum() < 4:
        return None
    d = S - R
    # The light: its pixels' summed difference against their noise, and its factor.
    sl, rl = float(S[light].sum()), float(R[light].sum())
    z_light = abs(sl - rl) / max(float(np.sqrt(var[light].sum())), 1e-30)
    f_light = sl / rl if rl > 0 else np.inf
    # The room: the curve's gain there (its change's chi^2 against the hand-in's difference), and the factor a
    # scale alone would fit, weighted by the noise (no pixel beyond a relative error of FLOOR).
    v = var[room] + (FLOOR * R[room]) ** 2
    dr, ch, rr = d[room], lead.change[room], R[room]
    gain = float(np.sum((dr * dr - (dr - ch) ** 2) / v))
    z_room = gain / np.sqrt(2.0 * dr.size)
    f_room = float(np.sum(S[room] * rr / v)) / max(float(np.sum(rr * rr / v)), 1e-300)
    if not (z_light >= CURVE_Z and abs(f_light - 1.0) >= LIGHT_EFFECT and z_room >= CURVE_Z and f_room > 0
            and abs(np.log(f_light / f_room)) >= np.log1p(LIGHT_EFFECT)):
        return None
    was, now = fmt_values(R[light].mean(axis=0), 1), fmt_values(S[light].mean(axis=0), 1)
    return ("value_curve", f"the light seen directly changed with the rest: its pixels, {was} in the reference on "
            f"average, are {now} here, on the same curve and not by the room's factor (a mistake in a path's "
            "weights, its depth or a surface leaves the light's own value alone; a wrong radiance scales it with the "
            "room), so the values were changed after they were rendered (each pixel, or each sample before the mean), "
            "on their way to the file (check every step between the render and the file: a tone map, a colour grade, "
            "an encoding, the conversion into the file's codes or bits)")


def bounced_light(fit, R: np.ndarray, depths: dict, mask: np.ndarray, labels: np.ndarray, test, better,
                  *, alpha: float) -> tuple[str, str] | None:
    """(family, words) of the bounced light alone changed (module docstring), or None. ``fit`` is the explanation's
    (its difference ``D``, weights and terms), ``depths`` the basis renders by path depth (2: the paths cut after
    their light sample at the first surface, :mod:`mcrt.grade.explain.basis`), ``test(change)`` the remainder test's
    verdict on a change (:func:`mcrt.grade.adequacy.remainder_test`, on ``mask``: the mirror's pixels are left out, as
    what it shows is the room's light seen sharp, which no smooth factor on the sphere describes); ``better(a, b)``
    whether candidate a fits better than b by :data:`mcrt.grade.adequacy.CONFIRM_Z`
    (:func:`mcrt.grade.adequacy.closeness` without the BIC's credit); ``alpha`` the bias test's level."""
    direct = depths.get(2)
    if direct is None or not _part_changed(fit, R, R - direct, direct, mask, labels, test, better, alpha=alpha):
        return None
    return ("bounced_light", "the difference as a whole lies in one part of the light: what each surface receives "
            "straight from the lamp is right (its shadows and shading fit the reference), while the light that bounced "
            "off other surfaces differs (a smooth factor on each surface's bounced light leaves only noise, and fits far "
            "better than one on its direct light or on the whole image): check each step after a path's first "
            "surface, the bounce's direction, the frame built about the normal and the hemisphere it samples, its pdf "
            "and weight, Russian roulette, and where the path ends")


def direct_light(fit, R: np.ndarray, depths: dict, mask: np.ndarray, labels: np.ndarray, test, better,
                 *, alpha: float) -> tuple[str, str] | None:
    """(family, words) of the first surface's direct light alone changed (module docstring), or None; the arguments
    are :func:`bounced_light`'s (``depths`` with 1, the light seen directly, and 2)."""
    seen, direct = depths.get(1), depths.get(2)
    if seen is None or direct is None or not _part_changed(fit, R, direct - seen, R - direct + seen, mask, labels,
                                                           test, better, alpha=alpha):
        return None
    return ("direct_light", "the difference as a whole lies in one part of the light: the light seen directly and the "
            "light that bounced off other surfaces are right, while the light the first surface a camera ray meets "
            "receives straight from the lamp differs, smoothly over each surface (a smooth factor on each surface's "
            "direct light leaves only noise, and fits far better than one on its bounced light or on the whole "
            "image): check the light sample there, the point drawn on the light and the pdf it is divided by, the "
            "distance and its fall-off, the cosines at both ends (the surface's normal, the light's), the shadow ray "
            "and what counts as blocked, and how the samples of a point are summed or averaged")


def sphere_alone(lead, confined: list[str], *, filtered: bool, misregistered: bool) -> tuple[str, str] | None:
    """(family, words) of the difference on the mirror sphere's own pixels alone (module docstring), or None.
    ``confined`` names the surfaces off whose pixels the difference is consistent with noise (each alone: the
    remainder test on the image less that surface's pixels); ``lead`` is a partial reading's lead (None beside none);
    ``filtered`` and ``misregistered`` what the structure check found (a filter's noise, displaced edges)."""
    if len(confined) != 1 or "sphere" not in confined[0] or filtered or misregistered:
        return None
    if lead is not None and lead.family in IMAGE_WIDE:
        return None
    return ("sphere_alone", "the difference lies on the mirror sphere's own pixels alone: off them, what is left is "
            "consistent with noise (its shadow, the room around it and what lights it are right), so what differs is "
            f"the sphere itself or what it shows: {SPHERE_WORDS}")


def _part_changed(fit, R: np.ndarray, part: np.ndarray, rest: np.ndarray, mask: np.ndarray, labels: np.ndarray, test,
                  better, *, alpha: float) -> bool:
    """Whether the difference is ``part`` of the image (H, W, 3) changed by a smooth factor per surface and channel,
    ``rest`` (the image less ``part``) right (the arguments are :func:`bounced_light`'s): the rest needs no factor of
    its own (a constant one per surface and channel, fitted beside the part's, differs from 1 nowhere: Bonferroni's
    bound, Holm's first step, at the bias test's level), the part's fit leaves only noise, the rest's does not, and
    the part's fits better than the rest's and the whole image's."""
    from mcrt.grade.candidates import Candidate

    R, part, rest = (np.asarray(x, np.float64) for x in (R, part, rest))
    w = np.where(fit.ok & mask[..., None], fit.w, 0.0)
    # Tested first: it is the cheapest to fail.
    z = smooth_fit(fit.D, part, w, labels, mask, also=rest)[2]
    if z.size and float(np.min(2.0 * norm.sf(np.abs(z)))) <= alpha / z.size:
        return False
    fits = {name: smooth_fit(fit.D, X, w, labels, mask) for name, X in (("part", part), ("rest", rest), ("whole", R))}
    c = {name: Candidate("part", name, name, fit.delta(ch), p, change=ch) for name, (ch, p, _) in fits.items()}
    return (test(c["part"].change) == "adequate" and test(c["rest"].change) != "adequate"
            and better(c["part"], c["rest"]) and better(c["part"], c["whole"]))


def smooth_fit(D: np.ndarray, X: np.ndarray, w: np.ndarray, labels: np.ndarray, mask: np.ndarray,
               order: int = SMOOTH_ORDER, *, also: np.ndarray | None = None):
    """The change X (F - 1) that fits the difference ``D`` best by weighted least squares (``w`` its weights, 0
    outside ``mask``), F a polynomial of degree ``order`` in the pixel's place, one per surface (``labels``) and
    channel, plus a constant factor g on ``also`` per surface and channel where given; the number of its
    coefficients, and each g's z-score (its value over its standard error). X and ``also`` are (H, W, 3): the parts
    of the image the factors act on."""
    h, wd = labels.shape
    v, u = np.mgrid[0:h, 0:wd]
    u, v = 2.0 * u / max(wd - 1, 1) - 1.0, 2.0 * v / max(h - 1, 1) - 1.0
    phi = np.stack([u**i * v**j for i in range(order + 1) for j in range(order + 1 - i)], axis=-1)
    out, params, z = np.zeros_like(np.asarray(D, np.float64)), 0, []
    for k in np.unique(labels[mask]):
        on = mask & (labels == k)
        for c in range(3):
            A = X[on, c][:, None] * phi[on]
            if also is not None:
                A = np.concatenate([A, also[on, c][:, None]], axis=1)
            Aw = A * np.sqrt(w[on, c])[:, None]
            keep = np.abs(Aw).sum(axis=0) > 0
            if not keep.any():
                continue
            coef, *_ = np.linalg.lstsq(Aw[:, keep], D[on, c] * np.sqrt(w[on, c]), rcond=None)
            out[on, c] = A[:, keep] @ coef
            params += int(keep.sum())
            if also is not None and keep[-1]:
                se = float(np.sqrt(np.linalg.pinv(Aw[:, keep].T @ Aw[:, keep])[-1, -1]))
                z.append(float(coef[-1]) / se if se > 0 else 0.0)
    return out, params, np.asarray(z)
