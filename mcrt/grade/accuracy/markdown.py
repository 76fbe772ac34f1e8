"""The grading-accuracy report: reports/grading_accuracy/index.md and data.json."""

from __future__ import annotations

import json
from importlib import import_module
from pathlib import Path

from mcrt.grade.accuracy.run import Outcome, rates


def _pct(r: dict) -> str:
    return "n/a" if r["rate"] is None else f"{r['k']}/{r['n']} ({100 * r['rate']:.0f} %)"


def _cell(text: str, limit: int = 260) -> str:
    t = " ".join(str(text).split()).replace("|", "/")
    return t if len(t) <= limit else t[: limit - 3] + "..."


_OUTSIDE = ("The wrong renders are mistakes made **outside the scene file** (mcrt.grade.accuracy.outside): "
            "Mitsuba renders of the right scene post-processed or written as a student's program does (tone maps, "
            "a clamp, BGR channels, a cosine weight per pixel, a lower resolution enlarged), Mitsuba renders with "
            "another material, light model or object size, and renders that claim more samples per pixel than they "
            "took; the correct ones come from Mitsuba and mcrt. Each is written as a student's folder and graded "
            "with the course assignment. *Named right*: the feedback claims the mistake's cause. *Confidently "
            "wrong*: it claims a cause (\"It looks like ...\", or a criterion that names one) and not the right "
            "one. *Partial or none*: it claims no cause and says what it can (\"partly like X; something else is "
            "wrong on ...\", \"it could be X, or Y: the image cannot tell which\", or where the difference sits): "
            "neither right nor wrong. **Held-out** cases (marked H) "
            "were chosen when the class was written and not graded until the rules were final, with one exception: "
            "after they were first graded, the monotone curve's fit was refined (64 bins, for curves outside both "
            "halves) and a family with more parameters was no longer named as an alternative beside a claimed "
            "cause (one held-out case, the radiance divided by pi, had a monotone curve named beside the constant "
            "factor); no held-out case changed its verdict. In the round that added the per-object structure test "
            "and the noise model that does not absorb a bias, the earlier round's held-out results were known (the "
            "glossy sphere's full marks motivated the test); the test was tuned on other renders (Mitsuba rough "
            "conductor spheres of alpha 0.05 to 0.3, correct renders at 16 to 1024 spp) and the tuned half, and the "
            "held-out half was graded only with the rules final; after that, one rule was dropped (a claimed blur "
            "counted as a filtered image by itself: it made correct renders that the false-alarm report already "
            "flags lose more points), and no held-out verdict changed. The same round added families tuned on the "
            "tuned half of the programs class (a colour matrix, light counted twice, the light facing, bad pixels, "
            "a black surface) without grading this class's held-out half; with them, the held-out `bgr_png` went "
            "from partial to named right (the colour matrix names BGR in an 8-bit PNG).")

_PROGRAMS = ("The wrong renders are mistakes of **students' programs** (mcrt.grade.accuracy.programs), written apart "
             "from the grader's rules and not graded by their author: images written flipped, mirrored or transposed, "
             "wrong encodings, colour lost, a constant factor, direct light counted twice, the path depth, the walls' "
             "colours, pixels not computed, a per-sample clamp, fewer samples than declared, and single scene "
             "mistakes, from Mitsuba renders of edited scenes, Mitsuba renders combined, or correct renders written "
             "as students' programs write files; the correct ones come from Mitsuba and mcrt. Each is written as a "
             "student's folder and graded with the course assignment. *Named right*, *confidently wrong*, *partial "
             "or none*: as for the other classes. **Held-out** cases (marked H) were fixed by the rule stated in the "
             "module before any case was graded.")


_FRESH = ("The wrong renders are mistakes **no other class tried** (mcrt.grade.accuracy.fresh), written apart from the "
          "grader's rules and not graded by their author: files written wrongly (8-bit codes truncated, a PFM's byte "
          "order, the image divided by its maximum, the display curve applied per sample, XYZ written as RGB), the "
          "light emitting from both faces, materials (a glossy coat, a tinted mirror, a default grey), normals facing "
          "the wrong way, a wall or a face missing, camera models (up negated, the field of view's tangent in the "
          "wrong unit, pixel centres mapped with W - 1, orthographic), resampling a 2x render, two renders with one seed, "
          "only the last pass written, and Russian roulette without re-weighting; from Mitsuba renders of edited "
          "scenes, Mitsuba renders combined, or correct renders written as students' programs write files. The "
          "correct ones come from Mitsuba and mcrt in formats no other class used. *Named right*, *confidently "
          "wrong*, *partial or none*: as for the other classes. **No case is held out any more**: the class was "
          "written after the other classes' held-out halves had been seen and graded once with every case held out "
          "(commit c4a8457, this report at that commit); the rules were then changed on what it showed (a PFM's "
          "byte order, a pair of one seed, a black surface's causes, a sub-pixel shift), so these are the rates of "
          "a class tuned on.")


_BLIND = ("The wrong renders are mistakes made **outside the scene file** that no other class tried "
          "(mcrt.grade.accuracy.blind), written blind to the grader's rules and not graded by their author: "
          "post-processing (a filmic curve, an exposure left in a sidecar, an unsharp mask, a saturation change), "
          "writing the file (a planar buffer as interleaved, 12-bit codes in a 16-bit PNG, a row stride off by one, a "
          "BMP's rows upside down), materials (a Lambertian divided by pi twice, albedos squared, a silver or "
          "glass-Fresnel mirror, a mirror floor), camera models (a thin lens, a diagonal field of view, a 4:3 aspect, "
          "jitter over two pixels), light models (radiance times area, a pdf without the area, a disk, one "
          "triangle sampled), resolution (63 or 65 pixels padded or cropped, a bicubic enlargement) and claimed "
          "spp (channels traced apart, "
          "adaptive stopping, an interrupted render); from Mitsuba renders of edited scenes, Mitsuba renders "
          "combined, or correct renders written as students' programs write files. The correct ones come from "
          "Mitsuba and mcrt in formats no other class used. *Named right*, *confidently wrong*, *partial or none*: "
          "as for the other classes (*partial or none* includes a difference described as a curve on the values with "
          "no cause claimed). **Held-out** cases (marked H) were fixed by the rule stated in the module (every "
          "other case of each category) before any case was graded. The rules were changed on the tuning half only "
          "(a curve no program applies described, not claimed; the encoding finding not judged where nothing "
          "explains the decoded image; a BRDF's normalisation, an aspect ratio, an unsharp mask, a render one pixel "
          "off, a bicubic enlargement, Hable's curve), and the held-out half was graded once, after the last change "
          "(this report at commit 377bbf5). **The held-out half is held out no more**: the next round changed the "
          "rules with that grading in view (a claim must fit better than a cause of another kind that fits too; a "
          "light sample's weight, every reflectance squared, a diagonal field of view), so its row here is of "
          "rules tuned on it.")


_UNSEEN = ("The wrong renders are a sixth class of mistakes in students' tracers and their output that no other class "
           "tried (mcrt.grade.accuracy.unseen), written blind to the grader's rules and not graded by their author: "
           "post-processing (Reinhard on the luminance, a vignette, a bloom, a grey-world white balance), writing the "
           "file (a hand-written 16-bit PNG little-endian, a PPM with a newline too many, a PFM headed grey, an HDR "
           "with exponents biased by 127), materials (a glass sphere, the tetrahedron's normals smoothed, an ambient "
           "term, the tetrahedron's colour decoded as sRGB), camera models (the far camera, up +y, jitter in x "
           "only), light models (the light sampled on one quadrant, shadow rays blocked by the light itself, the "
           "light sampled on its diagonal), resolution (a 2x render reduced in display codes or by sums, rows one "
           "place up, the course's 100 x 100 resized by nearest pixels) and samples per pixel (rows of one seed, the median of "
           "batches, two runs averaged with equal weights, a running mean halved each sample); from Mitsuba renders "
           "of edited scenes, Mitsuba renders combined, or correct renders written as students' programs write "
           "files. The correct ones come from Mitsuba and mcrt in ways no other class used. *Named right*, "
           "*confidently wrong*, *partial or none*: as for the other classes. **Held-out** cases (marked H) were "
           "fixed by the rule stated in the module (every other case of each category) before any case was graded. "
           "The rules were changed on the tuning half only (tone curves on the luminance, a bloom, the light "
           "sampled on a quarter, a 16-bit PNG's byte order, a PFM's data beyond its header, a flip claimed only for "
           "an image that resembles a view, noise correlated along one direction), and the held-out half was graded "
           "once, on the frozen rules: this report at commit c9f10bb (4 of 12 named right, 4 confidently wrong). "
           "Changes made after that grading, with it in view: a BRDF's normalisation only by a factor a program gets "
           "wrong, not any factor; a shift by a whole pixel worded as an index off by one, which names the row "
           "stride; a quarter turn's words naming the camera's up vector; a surface out of view never claimed on a "
           "fit alone; a render reduced from a larger one by nearest pixels; a PPM's raster starting late refused; "
           "and in the scoring, shadow rays blocked by the light's own surface accepted as the catalogue's shadow "
           "rays not bounded by the light's distance (the same mistake). The held-out row here is of rules that saw "
           "it.")


_UNTRIED = ("The wrong renders are a seventh class of mistakes in students' tracers, their scene input and their "
            "output that no other class or the catalogue tried (mcrt.grade.accuracy.untried), written blind to the "
            "grader's rules and not graded by their author: post-processing (a median filter, the render "
            "sRGB-decoded, a min-max stretch, a Display P3 conversion), writing the file (16-bit samples under an "
            "8-bit PPM header, 8-bit codes times 256 in a 16-bit PNG, a web palette, codes wrapped past 255), "
            "materials (a Lambertian over 2 pi, the mirror tinted with the tetrahedron's colour, the light "
            "reflecting), geometry (the sphere's radius taken for its diameter, the tetrahedron's apex mistyped, a "
            "faceted sphere, the sphere's centre truncated), camera models (pixel coordinates in [-0.5, 0.5], pixel "
            "indices from 1, the far eye with the near field of view, the jitter drawn once per pixel), light models "
            "(the radiance taken for power, 29 of 30 shadow rays, the light coplanar with the ceiling), resolution "
            "and pixel sampling (strata on the diagonal, the centre of a 100 x 100 render, rows copied) and samples "
            "per pixel (a direct-light preview kept in the mean, batches averaged as 8-bit PNGs, a sum divided by n +"
            " 1); from Mitsuba renders of edited scenes, Mitsuba renders combined, or correct renders written as "
            "students' programs write files. The correct ones come from Mitsuba and mcrt in ways no other class used."
            " *Named right*, *confidently wrong*, *partial or none*: as for the other classes. **Held-out** cases "
            "(marked H) were fixed by the rule stated in the module (every other case of each category) before any "
            "case was graded. The grader's rules were frozen at commit ac9cd66 before this class was graded, and "
            "the whole class was graded once, on them (report at commit 2febcf2: held out, 3 of 12 named right and 0 "
            "confidently wrong; all 28, 9 named right and 1 confidently wrong, the sphere's radius halved claimed as "
            "the sphere missing). Changes made after that grading, with the whole class in view: an object's size "
            "halved or doubled, the eye moved by a whole unit, the sRGB decoding of a float file (values above 1 "
            "decoded too), every other row or column copied, a netpbm file with twice the data its header declares "
            "refused, and in the scoring a shift by a whole pixel accepted as pixel indices off by one; later, still "
            "with it in view (commit 05d671d): 8-bit codes times 256 in a 16-bit PNG and 8-bit codes cast without a "
            "clip named under linear, and the field of view scanned from 0.62 times the scene's and worded as the "
            "middle of a larger render. Both rows here are of rules that saw the class.")


_NOVEL = ("The wrong renders are an eighth class of mistakes in students' tracers, their scene input and their output "
          "that no other class or the catalogue tried (mcrt.grade.accuracy.novel), written blind to the grader's rules "
          "and not graded by their author: post-processing (an automatic exposure, log1p of the values, a "
          "chromatic-aberration effect, a Bradford adaptation to D50), writing the file (a JPEG on the way to the PNG, "
          "float64 data under a PFM header, codes through an RGB565 framebuffer, an EXR of unsigned integers), "
          "materials (a wall's channels rotated, every albedo read as its red channel, a Phong sphere half diffuse), "
          "geometry (a room corner mistyped, the sphere's y negated, the sphere squashed to an ellipsoid, the "
          "tetrahedron scaled about the origin), camera models (a field of view in radians read as degrees, the "
          "camera looking at the sphere, a fisheye), light models (a spherical light, the light sampled on a "
          "parallelogram, the light seen at half its radiance, the light's centre taken for its corner), pixel "
          "sampling (offsets as the sum of two uniform numbers, Gaussian offsets, a constant offset) and samples per "
          "pixel (strata in one loop, spp and depth swapped, passes declared as one); from Mitsuba renders of edited "
          "scenes, Mitsuba renders combined, or correct renders written as students' programs write files. The "
          "correct ones come from Mitsuba and mcrt in ways no other class used. *Named right*, *confidently wrong*, "
          "*partial or none*: as for the other classes. **Held-out** cases (marked H) were fixed by the rule stated "
          "in the module (every other case of each category) before any case was graded. The grader's rules were "
          "frozen at commit 05d671d before this class was graded (the list of its mistakes had been read, not its code "
          "or images), and the whole class was graded once, on them (report at commit ec929c9: held out, 2 of 12 named "
          "right and 3 of 12 confidently wrong; all 28, 8 named right and 5 confidently wrong; one correct hand-in, "
          "Mitsuba's prb_basic without light sampling, 36 times noisier than its spp allows). Changes made after "
          "that grading, with the whole class in view (commits 7fee76d and 6f89570): the light seen directly at a "
          "factor as a family; a free colour matrix's words naming a change of colour space, a white balance or a "
          "chromatic adaptation (and the scoring accepting them for a white balance); one channel in all three "
          "worded also as every colour taken as one number; kept pixels worded also as every sample through one "
          "fixed point of its pixel; an EXR of integer channels refused naming the cast. Both rows here are of rules "
          "that saw the class. Until commit 1c13fbe the two jitter mistakes (tent and Gaussian offsets) were rendered "
          "with a box filter, a scene dictionary's film being reset to the reference's: correct renders graded as "
          "mistakes, at full marks in the frozen-rules report; they are rendered with their filter since.")


def _written_blind(nth: str, module: str) -> str:
    """The first sentences of the intro of a class written blind and graded once on frozen rules (untold, unmet,
    unheard, unsaid, unasked, unsought)."""
    return (f"The wrong renders are a {nth} class of mistakes in students' tracers, their scene input and their output "
            f"that no other class or the catalogue tried (mcrt.grade.accuracy.{module}), written blind to the grader's "
            "rules and not graded by their author: post-processing, writing the file, materials, geometry, camera and "
            "light models, the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba "
            "renders combined, or correct renders written as students' programs write files. The correct ones come "
            "from Mitsuba and mcrt in ways no other class used. *Named right*, *confidently wrong*, *partial or none*: "
            "as for the other classes. **Held-out** cases (marked H) were fixed by the rule stated in the module (every "
            "other case of each category) before any case was graded. Its author reported counts only (no mistake "
            "named) before the grader's rules were frozen at commit ")


_UNTOLD = _written_blind("ninth", "untold") + ("7f6f516; the whole class was then graded once, on them (report "
           "at commit eaed105: held out, 4 of 12 named right, 2 of 12 confidently wrong, 11 of 12 detected; all 28, "
           "8 named right, 4 confidently wrong, 26 detected; 0 of 8 correct hand-ins lost points). Changes made after "
           "that grading, with the whole class in view: noise in excess only on the light's outline worded as the "
           "outline differing (the light's position, size or shape, or its bright pixels filtered), not as fewer "
           "samples; the noise words naming passes that repeat one seed; black pixels that are one object's worded "
           "as that object black (for a mirror, paths through it never counted); the aspect family only at aspects "
           "a program hard-codes (4:3, 16:9, ...), not a free factor; the light seen directly at down to 1/50 of its "
           "radiance (clamped to 1); and, in the round after (commits a65f5db to d63c25f, before the unmet class was "
           "graded): 8-bit codes of linear values rounded before the curve, or cast before the scaling by 255; a black "
           "level subtracted; an object's coordinates read in another order; the floor or the ceiling at another "
           "height; a cylindrical, equirectangular or fisheye camera and a radial lens distortion. Both rows here are "
           "of rules that saw the class.")


_UNMET = _written_blind("tenth", "unmet") + ("089af9b (after a false-alarm report on them: 0 of 153); the whole "
          "class was then graded once, on them (report at commit af65c93: held out, 2 of 12 named right, 0 of 12 "
          "confidently wrong, 10 of 12 detected; all 28, 3 named right, 1 confidently wrong, 24 detected; 0 of 8 "
          "correct hand-ins lost points). Changes made after that grading, with the whole class in view: the direct "
          "light missing at the first surface hit; an object left about the origin (model space); the camera looking "
          "back; float values rounded to decimals, and a PNG of the sRGB curve's exponent alone, named under the "
          "encoding criterion (the latter losing its points). Both rows here are of rules that saw the class.")


_UNHEARD = _written_blind("eleventh", "unheard") + ("8ccc50a (after a false-alarm report on them: 0 of 153); the "
            "whole class was then graded once, on them (report at commit 82d1e33: held out, 6 of 12 named right, 0 of "
            "12 confidently wrong, 12 of 12 detected; all 28, 10 named right, 1 confidently wrong, 28 detected; 0 of 8 "
            "correct hand-ins lost points). Changes made after that grading, with the whole class in view: a path's "
            "weight off by a constant from a bounce on (rays summed where their mean belongs, a pdf off by a "
            "constant, roulette's survivors divided wrongly); the direct light missing at the surfaces seen in the mirror; "
            "a contrast control among the tone curves; a PNG of the "
            "gamma applied the wrong way round, named under the encoding criterion; a PPM holding an RGBA buffer "
            "refused, naming it; the pixel-shift words naming sub-pixel offsets not spread over the pixel. Both rows "
            "here are of rules that saw the class.")


_UNSAID = _written_blind("twelfth", "unsaid") + ("eef00ea (after a false-alarm report on them: 0 of 153); the "
           "whole class was then graded once, on them (report at commit 5cb921b: held out, 3 of 12 named right, 2 of "
           "12 confidently wrong, 12 of 12 detected; all 28, 5 named right, 2 confidently wrong, 27 detected; 0 of 8 "
           "correct hand-ins lost points). Changes made after that grading, with the whole class in view: lines of "
           "the image out of order named by the noise criterion (not as fewer samples); a mirror missing worded with "
           "rays passing through it unchanged; the exponential tone map among the named curves; and, in the round after "
           "(commits 36411d8 to c074e24, before the unasked class was graded): lines out of order fitted by the lines "
           "moved, and a row's or the image's channels written one after another; BT.709's curve; 3 x 3 filters "
           "(median, maximum, minimum, and box or binomial weights that do not sum to 1); albedos rounded to one "
           "decimal; N shadow rays summed where their mean belongs, with the noise a light sample's or a path's weight "
           "multiplies allowed in the remainder. Both rows here are of rules that saw the class.")


_UNASKED = _written_blind("thirteenth", "unasked") + ("c074e24 (after a false-alarm report on them: 0 of 153); "
           "the whole class was then graded once, on them (report at commit f90691c: held out, 1 of 12 named right, 1 "
           "of 12 confidently wrong, 12 of 12 detected; all 28, 9 named right, 3 confidently wrong, 28 detected; 0 of "
           "8 correct hand-ins lost points). Before the freeze a search of the source showed the grader's author some "
           "of the module's lines (among them two mistakes' names); the one change made after it came from a run over "
           "the other classes. Changes made after that grading, with the whole class in view: a factor two decimals "
           "would print as 0 given two significant digits; a patch of black pixels on one surface, all touching, "
           "worded as a hole in it; a 3 x 3 filter with a gain no other reading beside the overall scale it "
           "generalises (found by the fresh-clone suite). Both rows here are of rules that saw the class.")


_UNSOUGHT = (
    "The wrong renders are a fourteenth class of mistakes in students' tracers, their scene input and their output "
    "that no other class or the catalogue tried (mcrt.grade.accuracy.unsought), written blind to the grader's rules "
    "and not graded by their author: post-processing, writing the file, materials, geometry, camera and light models, "
    "the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba renders combined, or "
    "correct renders written as students' programs write files. The correct ones come from Mitsuba and mcrt in ways "
    "no other class used. *Named right*, *confidently wrong*, *partial or none*: as for the other classes. "
    "**Held-out** cases (marked H) were fixed by the rule stated in the module (every other case of each category) "
    "before any case was graded. Unlike the classes before it, its author's report named each mistake (name, "
    "category, cause, major, held out) and the correct hand-ins, and the grader's author read that list before the "
    "rules were frozen, not the module's code or its images. One change was made between reading it and the freeze, "
    "begun before the list arrived and prompted by the unsaid class's sphere left out of the shadow test: a test for "
    "patches of touching pixels off together (mcrt.grade.structure). The rules were frozen at commit 9a994c0 (after a "
    "false-alarm report on them: 0 of 153), and the whole class was graded once, on them (report at commit 571d40c: "
    "held out, 4 of 12 named right, 0 of 12 confidently wrong, 12 of 12 detected; all 28, 11 named right, 2 "
    "confidently wrong, 26 detected; 0 of 8 correct hand-ins lost points). Changes made after that grading, with the "
    "whole class in view: excess noise that most pixels do not share worded as a few pixels far off, not as fewer "
    "samples, and a catalogued bug named by its amount of noise only where its own excess lies; the orientation check "
    "comparing each view with the image's channels in the order that suits it best; the catalogue's black mirror "
    "worded beside a material that reflects little; and, in the round after (commits 2777094 and 3440cb8, before the "
    "unguessed class was graded): the display curve applied to some colour channels and not others, and a monotone "
    "curve that leaves structure never the lead of a partial claim; and, before the unprompted class was graded "
    "(commit 0998815), a light sampled elsewhere (the sampling code's own copy of the light), with this class's light "
    "sampled about (5.5, 0, 4.99) in view. Both rows here are of rules that saw the class.")


_UNGUESSED = (
    "The wrong renders are a fifteenth class of mistakes in students' tracers, their scene input and their output "
    "that no other class or the catalogue tried (mcrt.grade.accuracy.unguessed), written blind to the grader's rules "
    "and not graded by their author: post-processing, writing the file and its manifest, materials, geometry, camera "
    "and light models, the integrator, and samples and tiles; from Mitsuba renders of edited scenes, Mitsuba renders "
    "combined, or correct renders written as students' programs write files. The correct ones come from Mitsuba and "
    "mcrt in ways no other class used. *Named right*, *confidently wrong*, *partial or none*: as for the other "
    "classes. **Held-out** cases (marked H) were fixed by the rule stated in the module (every other case of each "
    "category) before any case was graded. The grader's rules were frozen at commit 3440cb8 before its author's "
    "report (which named the cases) arrived, and a false-alarm report on them gave 0 of 153; the whole class was then "
    "graded once, on them (report at commit 389b6c5: held out, 2 of 12 named right, 2 of 12 confidently wrong, 12 of "
    "12 detected; all 28, 5 named right, 5 confidently wrong, 26 detected; 0 of 8 correct hand-ins lost points). "
    "Changes made after that grading, with the whole class in view (commits ffc51ba to 2a71bb8, before the unforeseen "
    "class was graded, and fb0b997 after it): a constant factor worded also as a pixel's sum divided by another count "
    "than its samples'; a camera family claimed only where it fits beyond the emitters' outlines (kept as another "
    "reading where it does not); a misregistration beyond what a "
    "first-order fit measures worded without its numbers, naming the camera and where each pixel is written; the sRGB "
    "curve applied to the luminance among the curves; and, before the unprompted class was graded (commit bf4b76d), "
    "several surfaces' colours at once, with this class's albedos clamped at 0.7 in view, then (commit da4fc01) that "
    "family a candidate only where one colour moves by a tenth, after its light sampled unevenly had been claimed as "
    "two walls' colours. Both rows here are of rules that saw the class.")


_UNFORESEEN = (
    "The wrong renders are a sixteenth class of mistakes in students' tracers, their scene input and their output "
    "that no other class or the catalogue tried (mcrt.grade.accuracy.unforeseen), written blind to the grader's rules "
    "and not graded by their author: post-processing, writing the file, materials, geometry, camera and light models, "
    "the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba renders combined, or "
    "correct renders written as students' programs write files. The correct ones come from Mitsuba and mcrt in ways "
    "no other class used. *Named right*, *confidently wrong*, *partial or none*: as for the other classes. "
    "**Held-out** cases (marked H) were fixed by the rule stated in the module (every other case of each category) "
    "before any case was graded. Its author reported counts only (no case named or described); the grader's rules "
    "were frozen at commit 2a71bb8 and a false-alarm report on them gave 0 of 153 before any case was read or graded; "
    "the whole class was then graded once, on them (report at commit fdd939b: held out, 2 of 12 named right, 0 of 12 "
    "confidently wrong, 8 of 12 detected; all 28, 7 named right, 1 confidently wrong, 23 detected; 0 of 8 correct "
    "hand-ins lost points). One change was made after that grading, without this class in view: a camera change seen "
    "on the emitters' outlines alone kept as a reading beside the others (commit fb0b997, for another class's case "
    "that the rebuild of every report showed).")


_UNPROMPTED = (
    "The wrong renders are a seventeenth class of mistakes in students' tracers, their scene input and their output "
    "that no other class or the catalogue tried (mcrt.grade.accuracy.unprompted), written blind to the grader's rules "
    "and not graded by their author: post-processing, writing the file, materials, geometry, camera and light models, "
    "the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba renders combined, or "
    "correct renders written as students' programs write files. The correct ones come from Mitsuba and mcrt in ways "
    "no other class used. *Named right*, *confidently wrong*, *partial or none*: as for the other classes. "
    "**Held-out** cases (marked H) were fixed by the rule stated in the module (every other case of each category) "
    "before any case was graded. Its author reported counts only (no case named or described); the grader's rules "
    "were frozen at commit bf4b76d and a false-alarm report on them gave 0 of 153 before any case was read or "
    "graded; the whole class was then graded once, on them (report at commit a50b657: held out, 8 of 12 named right, 0 "
    "of 12 confidently wrong, 12 of 12 detected; all 28, 15 named right, 0 confidently wrong, 28 detected; 0 of 8 "
    "correct hand-ins lost points). The two families added just before the freeze (a light sampled elsewhere, several "
    "surfaces' colours at once) named two of the held-out eight. Changes made after that grading, with the whole "
    "class in view (commits 58470d7 to ef38100): a light sample's weight pi or 1/pi; the light's size along one side "
    "alone; a 3 x 3 filter whose border wraps round; a cause leads a partial reading only where it explains half the "
    "difference; a display file black where it must be white; another camera's view named only where its reference "
    "fits; another of the film's buffers (its variance, its squares) written for the mean; several surfaces' colours "
    "a candidate only where one moves by a tenth. Both rows here are of rules that saw the class.")

_UNBIDDEN = (
    "The wrong renders are an eighteenth class of mistakes in students' tracers, their scene input and their output "
    "that no other class or the catalogue tried (mcrt.grade.accuracy.unbidden), written blind to the grader's rules "
    "and not graded by their author: post-processing, writing the file, materials, geometry, camera and light models, "
    "the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba renders combined, or "
    "correct renders written as students' programs write files. The correct ones come from Mitsuba and mcrt in ways "
    "no other class used. *Named right*, *confidently wrong*, *partial or none*: as for the other classes. "
    "**Held-out** cases (marked H) were fixed by the rule stated in the module (every other case of each category) "
    "before any case was graded. Its author reported counts only (no case named or described); the grader's rules "
    "were frozen at commit c534d6e before any case was read or graded, and the whole class was then graded once, on "
    "them (report at commit 09b89ac: held out, 2 of 12 named right, 2 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 3 named right, 2 confidently wrong, 27 detected; 0 of 8 correct hand-ins lost points); no false-alarm report "
    "was made on the frozen rules alone. Five families added just before the freeze (the diffuse bounce and the "
    "mirror's reflection drawn wrongly, every wall one colour, the walls' colours permuted, an image shifted half a "
    "pixel) named none of the 28, and the last made one of the two confident wrongs: a 2 x 2 box filter, "
    "the same image as a half-pixel shift by interpolation, was claimed as the shift alone. Changes made after that "
    "grading, with the whole class in view (commit eafe813): that shift's words name the box filter it equals; the "
    "direct light missing on one surface or object (a tetrahedron never light-sampled, claimed as its colour, now "
    "read as either, no cause claimed); every albedo through a gamma of 2.2, the image plane's full width taken for "
    "its half, and surfaces emitting (commit 8b1d725; the ambient term among them dropped at 91c334c); the film's "
    "auxiliary buffers (commit 77b0780). Both rows here are of rules that saw the class.")

_UNHERALDED = (
    "The wrong renders are a nineteenth class of mistakes in students' tracers, their scene input and their output "
    "that no other class or the catalogue tried (mcrt.grade.accuracy.unheralded), written blind to the grader's rules "
    "and not graded by their author: post-processing, writing the file, materials, geometry, camera and light models, "
    "the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba renders combined, or "
    "correct renders written as students' programs write files. The correct ones come from Mitsuba and mcrt in ways "
    "no other class used. *Named right*, *confidently wrong*, *partial or none*: as for the other classes. "
    "**Held-out** cases (marked H) were fixed by the rule stated in the module (every other case of each category) "
    "before any case was graded. Its author reported counts only (no case named or described); the grader's rules "
    "were frozen at commit 8b1d725 before any case was read or graded, and the whole class was graded once, on them: "
    "this report (held out, 3 of 12 named right, 3 of 12 confidently wrong, 12 of 12 detected; all 28, 8 named right, "
    "6 confidently wrong, 26 detected; 0 of 8 correct hand-ins lost points). Changes made after that grading, with "
    "the whole class in view (commits 65166e2 and 0eeecec): every diffuse surface black, or of one colour; each pixel's samples "
    "combined by a median or a trimmed mean (rendered by mcrt); every row one row; a light sample's factor pi worded "
    "also as the BRDF's 1/pi left out; a flip's words counted as naming the camera's vectors; a power curve worded as "
    "an encoding counted for a tone curve; candidates of the first three readings tried before a fourth (commits "
    "after 65166e2 up to 91c334c: one surface emitting a flexible fit, the ambient term dropped, every row one row only "
    "where the lines are equal); the camera finding kept beside a camera reading tied with the closest, a netpbm "
    "file written as UTF-8 text refused with its cause, HDR video's PQ curve and a sigmoid contrast named, lines of "
    "one colour drawn over the image, the film's auxiliary buffers (commits 6187f81 to 77b0780). Both rows here are "
    "of rules that saw the class.")

_UNBEKNOWN = (
    "The wrong renders are a twentieth class of mistakes in students' tracers, their scene input and their output "
    "that no other class or the catalogue tried (mcrt.grade.accuracy.unbeknown), written blind to the grader's rules "
    "and not graded by their author: post-processing, writing the file, materials, geometry, camera and light models, "
    "the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba renders combined, "
    "Mitsuba's samples added up as students' loops add them, or correct renders written as students' programs write "
    "files. The correct ones come from Mitsuba and mcrt in ways no other class used. *Named right*, *confidently "
    "wrong*, *partial or none*: as for the other classes. **Held-out** cases (marked H) were fixed by the rule stated "
    "in the module (every other case of each category) before any case was graded. Its author reported counts only "
    "(no case named or described); the grader's rules were frozen at commit 77b0780 before any case was read or "
    "graded, and the whole class was graded once, on them: this report (held out, 3 of 12 named right, 1 of 12 "
    "confidently wrong, 11 of 12 detected; all 28, 6 named right, 2 confidently wrong, 25 detected; 0 of 8 correct "
    "hand-ins lost points). Changes made after that grading, with the whole class in view (commits ae49b92 to "
    "a33f1e6): black pixels where the light is hidden worded as the bounced light lost; Lambert's cosine taken to the "
    "eye; the camera turned a quarter; a mirror sending rays back; every object missing at once; every face of the "
    "room black; the first hit's light sample with its albedo left out or twice. Both rows here are of rules that "
    "saw the class.")

def _twin_blind(module: str, ordinal: str, frozen: str = "cca957e") -> str:
    """The opening of the introductions of two classes written blind the same day and graded once on the same rules,
    frozen at commit ``frozen`` (the twenty-first and twenty-second, the twenty-third and twenty-fourth, the
    twenty-fifth and twenty-sixth, the twenty-seventh and twenty-eighth, the twenty-ninth and thirtieth, the
    thirty-first and thirty-second, then the thirty-third and thirty-fourth)."""
    return (
        f"The wrong renders are a {ordinal} class of mistakes in students' tracers, their scene input and their output "
        f"that no other class or the catalogue tried (mcrt.grade.accuracy.{module}), written blind to the grader's "
        "rules and not graded by their author: post-processing, writing the file, materials, geometry, camera and "
        "light models, the integrator, and samples and passes; from Mitsuba renders of edited scenes, Mitsuba renders "
        "combined, Mitsuba's samples added up as students' loops add them, or correct renders written as students' "
        "programs write files. The correct ones come from Mitsuba and mcrt in ways no other class used. *Named "
        "right*, *confidently wrong*, *partial or none*: as for the other classes. **Held-out** cases (marked H) were "
        "fixed by the rule stated in the module (every other case of each category) before any case was graded. Its "
        f"author reported counts only (no case named or described); the grader's rules were frozen at commit {frozen} "
        "before any case of it or of its twin class was read or graded, and the whole class was graded once, on "
        "them: ")


#: What changed after the twin classes' one grading, with both in view.
_TWIN_AFTER = (
    " Changes made after that grading, with both classes in view (commits 610c411 to 014216e): the light sample's "
    "geometry term written wrongly (the light's cosine twice, clamped or taken with the surface's normal, a fall-off "
    "or a point light's attenuation, a spotlight's cone, the surface's cosine twice, a half-Lambert, the sample taken "
    "from the eye); the light's outline's words naming the camera's view too; black pixels where the light is "
    "hidden read with 1 % of them lit, and worded as Russian roulette on the radiance too; colour spaces' "
    "conversions; a median over the channels, OpenCV's Tonemap, the sRGB decoding's formula inverted, a coarse "
    "table of the sRGB curve; every albedo divided by its channels' sum. Both rows here are of rules that saw the "
    "class.")

_UNVISITED = _twin_blind("unvisited", "twenty-first") + (
    "this report's first grading (held out, 4 of 12 named right, 1 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 12 named right, 1 confidently wrong, 27 detected; 0 of 8 correct hand-ins lost points).") + _TWIN_AFTER

_UNLOOKED = _twin_blind("unlooked", "twenty-second") + (
    "this report's first grading (held out, 1 of 12 named right, 2 of 12 confidently wrong, 12 of 12 detected; all "
    "28, 6 named right, 4 confidently wrong, 27 detected; 0 of 8 correct hand-ins lost points).") + _TWIN_AFTER

#: What changed after the second pair of twin classes' one grading, with both in view.
_TWIN2_AFTER = (
    " Changes made after that grading, with both classes in view (commits b8576e1 to e19f1a5): Khronos' PBR Neutral "
    "tone map; the diffuse bounce weighted by its albedo's mean; white pixels holding 0 worded as a NaN cast too; "
    "the first hit's light samples averaged over the batch; a correct render's values in the wrong places. (Every "
    "diffuse reflectance times pi / 3 was tried and dropped: it fitted unheard's overlapping tiles to noise; the "
    "camera finding kept where no reading fits and the view differs, made before the freeze, was dropped: it named "
    "two garbled files' rows as a camera.) Both rows here are of rules that saw the class.")

_UNWONTED = _twin_blind("unwonted", "twenty-third", "5aa291d") + (
    "this report's first grading (held out, 2 of 12 named right, 0 of 12 confidently wrong, 12 of 12 detected; all "
    "28, 6 named right, 1 confidently wrong, 27 detected; 0 of 8 correct hand-ins lost points).") + _TWIN2_AFTER

_UNREMARKED = _twin_blind("unremarked", "twenty-fourth", "5aa291d") + (
    "this report's first grading (held out, 4 of 12 named right, 3 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 9 named right, 4 confidently wrong, 27 detected; 0 of 8 correct hand-ins lost points).") + _TWIN2_AFTER


def _borders_seen(case: str) -> str:
    """What changed later with a held-out 3 x 3 filter of three classes in view (the twenty-sixth's, the
    twenty-ninth's and the thirtieth's), said in each of them."""
    return (f" Changed later, with this class's held-out `{case}` in view beside two of other classes (commit "
            "2a41527): a 3 x 3 filter's border taking in zeros, left black, or a 'full' convolution cropped at its "
            "corner, where only the edge repeated and the opposite edge wrapped round had been tried (the three had "
            "been read as a filter with something else at the border, a tone map, or a zoom); every class was graded "
            "again on it. Its held-out row is of rules that saw that case.")


#: What changed after the third pair of twin classes' one grading, with both in view.
_TWIN3_AFTER = (
    " Changes made after that grading, with both classes in view (commits 5f5dcef and 57891fc): an object's geometry "
    "is said beside a partial reading only where what is left lies beside the object too (a cube map seen from the "
    "sphere's centre had been read as the sphere's geometry); a free colour matrix within 0.025 of one gain on every "
    "channel is no candidate (two 8-bit encodings a step off in the dark codes had been claimed as such matrices). "
    "Both rows here are of rules that saw the class.")

_UNREMEMBERED = _twin_blind("unremembered", "twenty-fifth", "9a0fc85") + (
    "this report's first grading (held out, 0 of 12 named right, 4 of 12 confidently wrong, 10 of 12 detected; all "
    "28, 3 named right, 4 confidently wrong, 25 detected; 0 of 8 correct hand-ins lost points).") + _TWIN3_AFTER

_UNNOTICED = _twin_blind("unnoticed", "twenty-sixth", "9a0fc85") + (
    "this report's first grading (held out, 3 of 12 named right, 1 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 7 named right, 1 confidently wrong, 26 detected; 1 of 8 correct hand-ins lost points, a held-out PPM of a "
    "correct render, 94.5).") + _TWIN3_AFTER + _borders_seen("pp_conv2_full_cropped")

#: What changed after the fourth pair of twin classes' one grading, with both in view.
_TWIN4_AFTER = (
    " Changes made after that grading, with both classes in view (commits b7fcedf and 579bae1): a curve on the values "
    "carries the noise it bends (a display curve steep near black grows a noisy render's noise, which the remainder "
    "test allows); a power curve clipped to 1, unless its exponent is within 0.05 of 1 (a clamp alone); the light "
    "sample's pdf left in area measure or converted without d^2 or the cosine at the light. Both rows here are of "
    "rules that saw the class.")

_UNRECORDED = _twin_blind("unrecorded", "twenty-seventh", "332f552") + (
    "this report's first grading (held out, 3 of 12 named right, 0 of 12 confidently wrong, 10 of 12 detected; all "
    "28, 12 named right, 2 confidently wrong, 26 detected; 0 of 8 correct hand-ins lost points).") + _TWIN4_AFTER

_UNATTENDED = _twin_blind("unattended", "twenty-eighth", "332f552") + (
    "this report's first grading (held out, 8 of 12 named right, 1 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 17 named right, 1 confidently wrong, 22 detected; 0 of 8 correct hand-ins lost points).") + _TWIN4_AFTER

#: What changed after the fifth pair of twin classes' one grading (decided from the other classes' rebuild on the
#: frozen rules, before either twin's report was read).
_TWIN5_AFTER = (
    " Changed after that grading, from the rebuild of the other classes on the same rules before this report was "
    "read (commit f3420b6): the light sampled over a rectangle of its plane is a candidate at every surface hit only, "
    "no longer at the first surface a camera ray meets alone (there it had claimed walls moved 0.1 inwards, a corner "
    "mistyped, a sphere's centre truncated and overlapping tiles); the cases whose feedback named such a rectangle "
    "were graded again on it, with no verdict of this class changed.")

_UNATTESTED = _twin_blind("unattested", "twenty-ninth", "892ae57") + (
    "this report's first grading (held out, 4 of 12 named right, 1 of 12 confidently wrong, 12 of 12 detected; all "
    "28, 8 named right, 6 confidently wrong, 28 detected; 0 of 8 correct hand-ins lost points).") + _TWIN5_AFTER + \
    _borders_seen("pp_torch_avg_pool_pad_counted")

_UNCONSIDERED = _twin_blind("unconsidered", "thirtieth", "892ae57") + (
    "this report's first grading (held out, 2 of 12 named right, 2 of 12 confidently wrong, 12 of 12 detected; all "
    "28, 6 named right, 4 confidently wrong, 27 detected; 0 of 8 correct hand-ins lost points).") + _TWIN5_AFTER + \
    _borders_seen("pp_java_convolveop_zero_edges")

#: What changed after the sixth pair of twin classes' one grading, with both in view.
_TWIN6_AFTER = (
    " Changed after that grading, with both classes in view (commit 1407620): every wall of one colour fitted black "
    "is worded as every wall black, naming every cause of black (a wall missing, albedo 0, normals facing away), as "
    "one wall's fit already was (the thirty-first class's walls built below the floor had been read as every wall of "
    "albedo 0.00); the cases whose feedback read every wall of one colour were graded again on it.")

_UNANTICIPATED = _twin_blind("unanticipated", "thirty-first", "b587739") + (
    "this report's first grading (held out, 3 of 12 named right, 2 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 10 named right, 2 confidently wrong, 27 detected; 0 of 8 correct hand-ins lost points).") + _TWIN6_AFTER

_UNEXAMINED = _twin_blind("unexamined", "thirty-second", "b587739") + (
    "this report's first grading (held out, 3 of 12 named right, 1 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 12 named right, 1 confidently wrong, 25 detected; 0 of 8 correct hand-ins lost points).") + _TWIN6_AFTER

#: What changed after the seventh pair of twin classes' one grading (not from either class).
_TWIN7_AFTER = (
    " Changed after that grading (commits 21d0b86 and a726d71), from an earlier class's report rebuilt beside these, "
    "not from either class: an image whose neighbouring pixels tie (a coarse palette; runs of black pixels aside) is "
    "not read as a tracer without light sampling, whatever the shape of its errors (that class's web-palette PNG had "
    "been). The class was graded again on it, and on later rules, when every class was rebuilt (the commit is in "
    "the report's meta).")

_UNCONFIRMED = _twin_blind("unconfirmed", "thirty-third", "2363b37") + (
    "this report's first grading (held out, 7 of 12 named right, 0 of 12 confidently wrong, 11 of 12 detected; all "
    "28, 13 named right, 2 confidently wrong, 26 detected; 0 of 8 correct hand-ins lost points).") + _TWIN7_AFTER

_UNLISTED = _twin_blind("unlisted", "thirty-fourth", "2363b37") + (
    "this report's first grading (held out, 4 of 12 named right, 0 of 12 confidently wrong, 10 of 12 detected; all "
    "28, 9 named right, 1 confidently wrong, 24 detected; 0 of 8 correct hand-ins lost points).") + _TWIN7_AFTER

#: Each class's title, after "Grading accuracy on a class of realistic hand-ins".
TITLES = {
    "outside": ": mistakes outside the scene file", "programs": ": mistakes of students' programs",
    "fresh": ": mistakes no other class tried",
    "blind": ": mistakes outside the scene file, written blind",
    "unseen": ": a sixth class of mistakes, written blind",
    "untried": ": a seventh class of mistakes, written blind",
    "novel": ": an eighth class of mistakes, written blind",
    "untold": ": a ninth class of mistakes, written blind",
    "unmet": ": a tenth class of mistakes, written blind",
    "unheard": ": an eleventh class of mistakes, written blind",
    "unsaid": ": a twelfth class of mistakes, written blind",
    "unasked": ": a thirteenth class of mistakes, written blind",
    "unsought": ": a fourteenth class of mistakes, written blind",
    "unguessed": ": a fifteenth class of mistakes, written blind",
    "unforeseen": ": a sixteenth class of mistakes, written blind",
    "unprompted": ": a seventeenth class of mistakes, written blind",
    "unbidden": ": an eighteenth class of mistakes, written blind",
    "unheralded": ": a nineteenth class of mistakes, written blind",
    "unbeknown": ": a twentieth class of mistakes, written blind",
    "unvisited": ": a twenty-first class of mistakes, written blind",
    "unlooked": ": a twenty-second class of mistakes, written blind",
    "unwonted": ": a twenty-third class of mistakes, written blind",
    "unremarked": ": a twenty-fourth class of mistakes, written blind",
    "unremembered": ": a twenty-fifth class of mistakes, written blind",
    "unnoticed": ": a twenty-sixth class of mistakes, written blind",
    "unrecorded": ": a twenty-seventh class of mistakes, written blind",
    "unattended": ": a twenty-eighth class of mistakes, written blind",
    "unattested": ": a twenty-ninth class of mistakes, written blind",
    "unconsidered": ": a thirtieth class of mistakes, written blind",
    "unanticipated": ": a thirty-first class of mistakes, written blind",
    "unexamined": ": a thirty-second class of mistakes, written blind",
    "unconfirmed": ": a thirty-third class of mistakes, written blind",
    "unlisted": ": a thirty-fourth class of mistakes, written blind"}

#: The scene class's introduction (mcrt.grade.accuracy.cases).
_SCENE = (
    "The wrong renders are **Mitsuba** renders of the scene edited the way a student's tracer goes wrong "
    "(mcrt.grade.accuracy.cases), not mcrt's catalogued mutants; the correct ones come from mcrt and from "
    "Mitsuba's `path` and `volpath` with several samplers, 16 to 1024 spp, as EXR or 8-bit PNG. Each is "
    "written as a student's folder and graded with the course assignment. *Named right*: the feedback names "
    "the mistake's cause (the explanation's family, or a criterion that names it: `linear` for an encoding, "
    "`exposure` for a constant factor, `camera` for misregistration). *Confidently wrong*: it names a cause, and "
    "not the right one; *also wrong*: it names the right cause and a wrong one beside it. **Held-out** cases (marked H) were not looked at while the diagnosis was tuned, with one exception: the last two rules of the grader (the camera not blamed beside a cause outside it; an explained wrong geometry, light placement, colour or camera scored as a major mistake) were added after the held-out results had been seen; and when the per-object structure test was added, the exemption of a blur's remainder where the detectors found a filter (a denoiser's kernel is no Gaussian) was added after the held-out `denoised` case had been seen to lose its name, and a rule (a claimed blur counted as a filtered image by itself) was dropped after the final run, with no held-out verdict changed.")

#: Each class's introduction (the scene class's is :data:`_SCENE`).
INTROS = {"outside": _OUTSIDE, "programs": _PROGRAMS, "fresh": _FRESH, "blind": _BLIND, "unseen": _UNSEEN,
          "untried": _UNTRIED, "novel": _NOVEL, "untold": _UNTOLD, "unmet": _UNMET, "unheard": _UNHEARD,
          "unsaid": _UNSAID, "unasked": _UNASKED, "unsought": _UNSOUGHT, "unguessed": _UNGUESSED,
          "unforeseen": _UNFORESEEN, "unprompted": _UNPROMPTED, "unbidden": _UNBIDDEN, "unheralded": _UNHERALDED,
          "unbeknown": _UNBEKNOWN, "unvisited": _UNVISITED, "unlooked": _UNLOOKED, "unwonted": _UNWONTED,
          "unremarked": _UNREMARKED, "unremembered": _UNREMEMBERED, "unnoticed": _UNNOTICED,
          "unrecorded": _UNRECORDED, "unattended": _UNATTENDED, "unattested": _UNATTESTED,
          "unconsidered": _UNCONSIDERED, "unanticipated": _UNANTICIPATED, "unexamined": _UNEXAMINED,
          "unconfirmed": _UNCONFIRMED, "unlisted": _UNLISTED}


def _regraded(r: dict | list[dict]) -> list[str]:
    """The lines that say which cases were graded again after the run, on which commit and why: one a record (a list
    of records, later ones on later commits; a case is in the last record that graded it)."""
    out = []
    for rec in r if isinstance(r, list) else [r]:
        many = len(rec["cases"]) > 1
        out.append(f"After this run, the case{'s' if many else ''} {', '.join(f'`{n}`' for n in rec['cases'])} "
                   f"{'were' if many else 'was'} graded again on commit {rec['commit']} ({rec['why']}); "
                   f"{'their rows' if many else 'its row'} and the rates are of that commit's rules.")
    return out


def write_report(out: str | Path, outcomes: list[Outcome], *, command: str, meta: dict, gradescope: list[dict],
                 klass: str = "scene") -> Path:
    """Write index.md and data.json under ``out``; returns the Markdown's path. ``klass`` is the class graded:
    'scene' (mcrt.grade.accuracy.cases) or another name of :data:`mcrt.grade.accuracy.cli.CLASSES` ('outside',
    'programs', 'fresh', ..., 'unrecorded', 'unattended', 'unattested', 'unconsidered', 'unanticipated', 'unexamined', 'unconfirmed', 'unlisted': the module of that name under
    mcrt.grade.accuracy); an empty half (tuned on or held out) is left out of the rates table."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    tuned = [o for o in outcomes if not o.held_out]
    held = [o for o in outcomes if o.held_out]
    groups = {"all": rates(outcomes), "tuned on": rates(tuned), "held out": rates(held)}
    data = {"command": command, "meta": meta, "rates": groups, "gradescope": gradescope,
            "cases": [o.to_dict() for o in outcomes]}
    (out / "data.json").write_text(json.dumps(data, indent=1, default=str) + "\n", encoding="utf-8")
    title = "Grading accuracy on a class of realistic hand-ins" + TITLES.get(klass, "")
    L = [f"# {title}", "",
         f"Written by `{command}` ({meta.get('date', '')}, {meta.get('seconds', 0):.0f} s). "
         f"Assignment: `{meta.get('assignment')}`; reference: {meta.get('reference')}.", "",
         *((line for rec in _regraded(meta["regraded"]) for line in (rec, "")) if meta.get("regraded") else ()),
         INTROS.get(klass, _SCENE), "",
         "## Rates", "",
         "| | mistakes | detected (lost points) | named right | confidently wrong | partial or none | also wrong | "
         "major mistakes losing >= 25 % | correct renders | false alarms | correct named a bug |",
         "|---|---|---|---|---|---|---|---|---|---|---|"]
    for g, r in groups.items():
        if r["mistakes"] + r["correct"] == 0 and g != "all":  # a class with no tuned (or no held-out) half
            continue
        L.append(f"| {g} | {r['mistakes']} | {_pct(r['detected'])} | {_pct(r['named_right'])} | {_pct(r['named_wrong'])} | "
                 f"{_pct(r['honest_partial'])} | {_pct(r['also_named_wrong'])} | "
                 f"{_pct(r['major_lost_a_quarter'])} | {r['correct']} | {_pct(r['false_alarms'])} | "
                 f"{_pct(r['correct_named_a_bug'])} |")
    L += ["", "## Wrong renders", "",
          "| case | H | mistake | cause | major | spp | file | score | named | the feedback says | s |",
          "|---|---|---|---|---|---|---|---|---|---|---|"]
    for o in outcomes:
        if o.cause is None:
            continue
        named = ("right, and a wrong one" if o.also_wrong else "right") if o.right else (
            "confidently wrong" if o.wrong else (o.verdict or "none"))
        L.append(f"| {o.name} | {'H' if o.held_out else ''} | {_cell(o.truth, 90)} | {o.cause} | {'yes' if o.major else 'no'} | "
                 f"{o.spp} | {o.file} | {o.score:g}/{o.max_score:g} | {named} | {_cell(o.said)} | {o.seconds:.1f} |")
    L += ["", "## Correct renders", "",
          "| case | H | render | spp | file | score | named a bug | the feedback says | s |", "|---|---|---|---|---|---|---|---|---|"]
    for o in outcomes:
        if o.cause is not None:
            continue
        L.append(f"| {o.name} | {'H' if o.held_out else ''} | {_cell(o.truth, 90)} | {o.spp} | {o.file} | "
                 f"{o.score:g}/{o.max_score:g} | {'yes' if o.wrong else 'no'} | {_cell(o.said) or '-'} | {o.seconds:.1f} |")
    causes = import_module(f"mcrt.grade.accuracy.{'cases' if klass == 'scene' else klass}").CAUSES
    L += ["", "Causes: " + "; ".join(f"`{k}` {v}" for k, v in causes.items()) + "."]
    L += _gradescope_section(gradescope, meta)
    path = out / "index.md"
    path.write_text("\n".join(L) + "\n", encoding="utf-8")
    return path


def _gradescope_section(gradescope: list[dict], meta: dict) -> list[str]:
    """The report's lines on one student as Gradescope grades it (none without timings)."""
    if not gradescope:
        return []
    L = ["", "## One student as Gradescope grades it", "",
         "A fresh process imports mcrt, loads the prepared context (the grading cache, as workers receive it) "
         "and grades one student (mcrt.grade.accuracy.run.gradescope_figures): the mistakes and the correct render "
         "that took longest to grade above. Gradescope's defaults: half a "
         "vCPU, 768 MB, a 10-minute timeout; under half a vCPU the wall time is about twice the CPU time.", "",
         "| case | exit | score | CPU s (process) | CPU s (grading) | wall s here | peak memory MB | context MB |",
         "|---|---|---|---|---|---|---|---|"]
    for g in gradescope:
        gc = "-" if g.get("grading_cpu_s") is None else f"{g['grading_cpu_s']:.1f}"
        mem = "-" if g.get("peak_rss_mb") is None else f"{g['peak_rss_mb']:.0f}"
        L.append(f"| {g['case']} | {g['exit']} | {g.get('score')} | {g['cpu_s']:.1f} | {gc} | {g['wall_s']:.1f} | "
                 f"{mem} | {g['context_mb']:.1f} |")
    prep = meta.get("prepare_seconds", 0)
    L += ["", "Building the cache (`mcrt grade --prepare`, references, catalogue and the explanation's "
         "variations): " + (f"{prep:.0f} s here." if prep >= 1 else f"already built by an earlier run (loading it took {prep:.1f} s).")]
    return L
