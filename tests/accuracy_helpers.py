"""What the accuracy classes' tests share: a case's spec by name, one hand-in built at a tiny size, and a random
image for the post-processes and writers (the classes' modules are mcrt.grade.accuracy.*)."""

from __future__ import annotations

import numpy as np

from mcrt.grade.accuracy.cases import build_class

W = H = 16


def by_name(specs, name: str):
    """The spec called ``name`` among ``specs``."""
    return next(s for s in specs if s.name == name)


def build(spec, size: int = W):
    """The hand-in of ``spec`` built at ``size`` x ``size`` pixels (never graded)."""
    return build_class(width=size, height=size, specs=(spec,))[0]


def image(seed: int = 3) -> np.ndarray:
    """An (H, W, 3) image of values in [0.05, 0.95] from ``seed``."""
    return np.random.default_rng(seed).random((H, W, 3)) * 0.9 + 0.05


def check_held_out_rule(klass, *, first_kept: bool = True) -> None:
    """Class module ``klass``'s held-out flags are its rule's: half of each category (never its first case when
    ``first_kept``) and half of its correct hand-ins."""
    assert {s.name: s.held_out for s in klass.SPECS} == klass.held_out_rule()
    held = {s.name for s in klass.SPECS if s.held_out}
    for names in klass.CATEGORIES.values():
        assert len(held & set(names)) == len(names) // 2
        assert not first_kept or names[0] not in held
    assert sum(s.held_out for s in klass.CORRECT) == len(klass.CORRECT) // 2


def check_not_catalogued(klass) -> None:
    """No case of class module ``klass`` bears the name of a catalogued bug."""
    from mcrt.mutants import CATALOGUE

    assert not set(CATALOGUE) & {s.name for s in klass.SPECS}


def check_specs(klass, earlier, *, mistakes: int) -> None:
    """Class module ``klass`` is well formed beside the ``earlier`` class modules: new case names and new causes,
    every mistake's cause worded, correct hand-ins without one, 8 categories of 3 to 5 that list every mistake, at
    least ``mistakes`` mistakes and 8 correct hand-ins."""
    from mcrt.grade.accuracy import cases, outside

    names = [s.name for s in klass.SPECS]
    assert len(names) == len(set(names))
    assert not {s.name for m in earlier for s in m.SPECS} & set(names)
    assert all(s.cause in klass.CAUSES and klass.CAUSES[s.cause] for s in klass.MISTAKES)
    assert all(s.cause is None for s in klass.CORRECT)
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in earlier for c in getattr(m, "NEW_CAUSES", ())}
    assert not old & set(klass.NEW_CAUSES) and set(klass.NEW_CAUSES) <= set(klass.CAUSES)
    listed = [n for names in klass.CATEGORIES.values() for n in names]
    assert sorted(listed) == sorted(s.name for s in klass.MISTAKES)
    assert len(klass.CATEGORIES) == 8 and all(3 <= len(v) <= 5 for v in klass.CATEGORIES.values())
    assert len(klass.MISTAKES) >= mistakes and len(klass.CORRECT) == 8


def check_builds(spec, folder, *, floor: float = -1e-3) -> None:
    """``spec``'s hand-in builds at W x H (finite, no value under ``floor``), is written as a student's folder under
    ``folder`` whose image reads back at that size, and its manifest declares the spp the spec does."""
    from mcrt.grade.accuracy.cases import write_submission
    from mcrt.image_files import read_image

    case = build(spec)
    assert case.image.shape == (H, W, 3) and np.all(np.isfinite(case.image)) and case.image.min() >= floor
    path = write_submission(case, folder)
    assert read_image(path).mean.shape == (H, W, 3)
    assert (folder / "manifest.toml").read_text().startswith(f"spp = {spec.declared_spp or case.spp}")


def plain(size: int, spp: int = 256) -> np.ndarray:
    """A correct Mitsuba render (the accuracy classes' default spec) at ``size`` x ``size`` pixels, ``spp`` samples."""
    from mcrt.grade.accuracy.cases import Spec

    return build_class(width=size, height=size, specs=(Spec("plain", None, spp=spp),))[0].image


def check_old_causes(klass, earlier) -> None:
    """Class module ``klass`` words every mistake by a cause of the ``earlier`` class modules and adds none, so
    SAME_MISTAKE needed no new entry."""
    from mcrt.grade.accuracy import cases, outside

    assert klass.NEW_CAUSES == {}
    old = set(cases.CAUSES) | set(outside.CAUSES) | {c for m in earlier for c in getattr(m, "NEW_CAUSES", ())}
    assert {s.cause for s in klass.MISTAKES} <= old


def check_seeds(klass, earlier, lo: int) -> None:
    """Class module ``klass``'s seeds lie in [lo, lo + 100000), where no ``earlier`` class module's seed for its names
    falls."""
    names = [s.name for s in klass.SPECS]
    assert all(lo <= klass._crc(n) < lo + 100000 for n in names)
    for m in earlier:
        if hasattr(m, "_crc"):
            assert not any(lo <= m._crc(n) < lo + 100000 for n in names), m.__name__


def check_command(klass, name: str) -> None:
    """``mcrt grade-accuracy --class name`` grades class module ``klass``'s specs."""
    import importlib

    from mcrt.grade.accuracy.cli import CLASSES

    assert importlib.import_module(f"mcrt.grade.accuracy.{CLASSES[name]}").SPECS is klass.SPECS


def check_new_truths(klass, earlier) -> None:
    """Every case of class module ``klass`` says what it is, in words no ``earlier`` class module's case uses."""
    assert all(s.truth for s in klass.SPECS)
    assert not {s.truth for m in earlier for s in m.SPECS} & {s.truth for s in klass.SPECS}


def pillow_codes(path) -> np.ndarray:
    """The 8-bit RGB codes of an image file as Pillow decodes them."""
    from PIL import Image

    return np.asarray(Image.open(path).convert("RGB"))


def check_correct_agree(klass, plain: np.ndarray) -> None:
    """Every correct hand-in of class module ``klass``, built at W x H, agrees with ``plain`` (a correct render of
    that size): its median pixel within 15 %, its mean within 10 %."""
    for s in klass.CORRECT:
        case = build(s)
        rel = np.abs(case.image - plain).mean(axis=2) / (plain.mean(axis=2) + 0.05)
        assert np.median(rel) < 0.15 and case.image.shape == (H, W, 3), s.name
        assert abs(case.image.mean() / plain.mean() - 1) < 0.1, s.name
