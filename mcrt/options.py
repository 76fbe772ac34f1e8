"""The path estimator's inputs, one dataclass per purpose.

==================  ==========================================================
part                what it holds
==================  ==========================================================
:class:`Settings`   the render settings: depth, light samples, roulette depth,
                    MIS, hidden emitters
:class:`Mutations`  the catalogued bugs (:mod:`mcrt.mutants`): every field's
                    default is the correct physics, each other value one bug
:class:`Tricks`     efficiency tricks (:mod:`mcrt.tricks` studies them): each
                    off at its default
:class:`Caustics`   how the path tracer shares the paths eye D ... D S+ L with
                    :mod:`mcrt.bidir`'s light tracer
==================  ==========================================================

:class:`EstimatorOptions` holds one of each; :meth:`EstimatorOptions.build`
takes flat field names (as the command line and the catalogue give them) and
sends each to its part. Names are unique across the parts.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

UNBOUNDED = 2**32 - 1

#: How a Lambertian direction is drawn (mcrt.bsdf.sample_lambertian): correctly, or by two catalogued mistakes.
LAMBERTIAN_SAMPLERS = ("cosine", "uniform_as_cosine", "ball_plus_normal")

#: How a diffuse bounce is drawn and weighted (mcrt.bsdf.mistaken_bounce): correctly ('cosine'), or by one of the
#: mistakes students' tracers make that the grader's explanation renders (mcrt.grade.explain.bounce); 'zero', the
#: bounce carrying nothing on, is what that explanation scales the others' light against.
BOUNCES = ("cosine", "uniform_sphere", "cosine_squared", "local_frame", "half_azimuth_duff", "half_azimuth_axis",
           "half_azimuth_cross", "disk_radius_u", "no_albedo", "times_pdf", "albedo_mean", "zero")
#: Where a bounce (or mirror) mistake applies: at every vertex, or at the first vertex of a camera path only.
BOUNCE_AT = ("every", "first")
#: How a mirror reflects (mcrt.bsdf.mistaken_mirror): correctly ('reflect'), or by one of the mistakes students'
#: tracers make that the grader's explanation renders (mcrt.grade.explain.mirror).
MIRRORS = ("reflect", "without_2", "normal_unnormalised", "normal_from_origin", "cosine_weighted", "camera_only",
           "backwards")

#: How a pixel's samples make its value (mcrt.film.pixel_statistic): their mean ('mean'), or a statistic students'
#: programs take against fireflies that the grader's explanation renders (mcrt.grade.explain.pixel_statistic): the
#: median, or the mean with the lowest and highest 5 % or 10 % dropped (scipy.stats.trim_mean).
PIXEL_STATISTICS = ("mean", "median", "trimmed_5", "trimmed_10")

#: What the path tracer does with the paths eye D ... D S+ L (Caustics.mode).
MIRROR_CAUSTICS = ("all", "skip", "only", "mis")

#: Light sampling strategies: uniform in area on the light, or uniform in the solid angle it subtends
#: (the spherical rectangle of :func:`mcrt.sampling.square_to_spherical_rectangle`).
LIGHT_SAMPLING = ("area", "solid_angle", "none")


@dataclass(frozen=True)
class Settings:
    """The render settings the estimator takes (from :class:`mcrt.scene.RenderSettings` and the renderer)."""

    max_depth: int = 8  # longest path in segments; -1 unbounded
    light_samples: int = 1  # K, points sampled on the light per Lambertian vertex
    rr_depth: int = 5  # depth from which Russian roulette runs
    mis: bool = False  # combine light samples and the cosine direction by the balance heuristic
    hide_emitters: bool = False  # do not count emitters seen directly from the eye

    def __post_init__(self):
        if self.max_depth < -1:
            raise ValueError(f"max_depth must be -1 (unbounded) or >= 0, got {self.max_depth}")
        if self.light_samples < 1:
            raise ValueError(f"light_samples must be >= 1, got {self.light_samples}")
        if self.rr_depth < 1:
            raise ValueError(f"rr_depth must be >= 1, got {self.rr_depth}")


@dataclass(frozen=True)
class Mutations:
    """The estimator's physics switches: the defaults are the correct estimator, each other value a catalogued bug.

    :data:`mcrt.mutants.CATALOGUE` names the values; ``roulette`` is also a
    renderer option, because the tricks study compares the course's scheme.
    """

    lambertian_sampler: str = "cosine"  # LAMBERTIAN_SAMPLERS
    brdf_inv_pi: bool = True  # the Lambertian BRDF is albedo / pi
    nee_cos_surface: bool = True  # the geometry term has the cosine at the receiver
    nee_cos_light: bool = True  # ... the cosine at the light
    nee_inv_dist2: bool = True  # ... the 1 / d^2
    nee_pdf_area: bool = True  # the light sample is divided by its area density (1 / A for one light)
    count_emission: str = "unsampled"  # 'unsampled': where no light sample found it; 'always': counted twice
    roulette: str = "unbiased"  # 'unbiased', or 'course2023': absorb with 0.75, else times 0.8
    mirror_sign: float = 1.0  # -1: the mirror reflects the wrong way
    extra_depth: int = 0  # segments added to a bounded max_depth
    spawn_offset: bool = True  # rays leave a surface from an offset origin
    shadow_bounded: bool = True  # shadow rays stop short of the light point
    light_one_sided: bool = True  # the light emits from the side its normal points to only

    def __post_init__(self):
        if self.lambertian_sampler not in LAMBERTIAN_SAMPLERS:
            raise ValueError(f"lambertian_sampler must be one of {', '.join(LAMBERTIAN_SAMPLERS)}")
        if self.count_emission not in ("unsampled", "always"):
            raise ValueError("count_emission must be 'unsampled' or 'always'")
        if self.roulette not in ("unbiased", "course2023"):
            raise ValueError("roulette must be 'unbiased' or 'course2023'")


@dataclass(frozen=True)
class Tricks:
    """Efficiency tricks, each off at its default (the estimator above, bit for bit)."""

    roulette_survival: float | None = None  # fixed survival probability; None: the scheme's (min(max beta, 0.95); 0.25)
    roulette_start: int | None = None  # first depth roulette runs at; None: the scheme's (rr_depth; 1)
    # 'area': uniform on the light; 'solid_angle': uniform in its solid angle; 'none': no next-event estimation, the
    # light found only where a bounce's direction meets it (correct, and far noisier: a student's tracer without light
    # sampling, whose noise the grader tells from fewer samples by its shape, mcrt.grade.stages.noise).
    light_sampling: str = "area"
    # Each camera path's radiance clamped per channel to this before it is added (fireflies removed, with their
    # energy: biased); None: no clamp. A student's mistake the grader's explanation renders (mcrt.grade.explain).
    sample_clamp: float | None = None
    # The diffuse bounce drawn or weighted as a student's tracer gets it wrong (BOUNCES), at BOUNCE_AT's vertices.
    # Another mistake the explanation renders; 'cosine' is the estimator above.
    bounce: str = "cosine"
    bounce_at: str = "every"
    # The mirror's reflection computed as a student's tracer gets it wrong (MIRRORS), at BOUNCE_AT's vertices; the
    # length of the sphere's normal left unnormalised (its radius) for 'normal_unnormalised'.
    mirror: str = "reflect"
    mirror_at: str = "every"
    mirror_normal_length: float = 1.0
    # How the film makes a pixel's value of its samples (PIXEL_STATISTICS): 'mean' is the estimator's image; another
    # statistic is a student's mistake the explanation renders (the estimator's paths are the same).
    pixel_statistic: str = "mean"

    def __post_init__(self):
        if self.bounce not in BOUNCES:
            raise ValueError(f"bounce must be one of {', '.join(BOUNCES)}, got {self.bounce!r}")
        if self.bounce_at not in BOUNCE_AT:
            raise ValueError(f"bounce_at must be one of {', '.join(BOUNCE_AT)}, got {self.bounce_at!r}")
        if self.mirror not in MIRRORS:
            raise ValueError(f"mirror must be one of {', '.join(MIRRORS)}, got {self.mirror!r}")
        if self.mirror_at not in BOUNCE_AT:
            raise ValueError(f"mirror_at must be one of {', '.join(BOUNCE_AT)}, got {self.mirror_at!r}")
        if self.pixel_statistic not in PIXEL_STATISTICS:
            raise ValueError(f"pixel_statistic must be one of {', '.join(PIXEL_STATISTICS)}, got {self.pixel_statistic!r}")
        if not self.mirror_normal_length > 0.0:
            raise ValueError(f"mirror_normal_length must be > 0, got {self.mirror_normal_length}")
        if self.sample_clamp is not None and not self.sample_clamp > 0.0:
            raise ValueError(f"sample_clamp must be > 0, got {self.sample_clamp}")
        if self.roulette_survival is not None and not 0.0 < self.roulette_survival <= 1.0:
            raise ValueError(f"roulette_survival must be in (0, 1], got {self.roulette_survival}")
        if self.roulette_start is not None and self.roulette_start < 1:
            raise ValueError(f"roulette_start must be >= 1, got {self.roulette_start}")
        if self.light_sampling not in LIGHT_SAMPLING:
            raise ValueError(f"light_sampling must be one of {', '.join(LIGHT_SAMPLING)}, got {self.light_sampling!r}")


@dataclass(frozen=True)
class Caustics:
    """The paths eye D ... D S+ L (first vertex diffuse, last a mirror), for :mod:`mcrt.bidir`.

    ``mirror_caustics`` 'all' counts them (plain path tracing); 'skip'
    leaves them to the light tracer; 'only' counts them alone (to check the
    light tracer); 'mis' counts them with the balance weight against the
    light tracer, whose densities the estimator is given
    (:class:`mcrt.estimator.PathEstimator`'s ``caustic_pdfs``).
    ``caustic_light_paths`` > 0 (with 'mis' and 'only') turns on balance
    weights: the light subpaths per camera sample of a pixel.
    """

    mirror_caustics: str = "all"
    caustic_light_paths: float = 0.0

    def __post_init__(self):
        if self.mirror_caustics not in MIRROR_CAUSTICS:
            raise ValueError(f"mirror_caustics must be one of {', '.join(MIRROR_CAUSTICS)}, got {self.mirror_caustics!r}")
        if (self.mirror_caustics == "mis" and self.caustic_light_paths <= 0) or (
                self.caustic_light_paths and self.mirror_caustics not in ("mis", "only")):
            raise ValueError("mirror_caustics 'mis' needs caustic_light_paths > 0, and only 'mis' and 'only' take them")


PARTS = {"settings": Settings, "mutations": Mutations, "tricks": Tricks, "caustics": Caustics}


@dataclass(frozen=True)
class EstimatorOptions:
    """Everything :class:`mcrt.estimator.PathEstimator` is told, by purpose (module docstring)."""

    settings: Settings = field(default_factory=Settings)
    mutations: Mutations = field(default_factory=Mutations)
    tricks: Tricks = field(default_factory=Tricks)
    caustics: Caustics = field(default_factory=Caustics)

    def __post_init__(self):
        if self.tricks.light_sampling == "solid_angle" and self.settings.mis:
            # Its weight Le cos_x Omega is bounded, which is what MIS is there for; the MIS weight of a
            # light hit would need the solid angle seen from the ray's origin, which no host provides.
            raise ValueError("solid-angle light sampling runs without MIS (its weight is bounded)")
        if self.tricks.light_sampling == "none" and self.settings.mis:
            raise ValueError("without light sampling there is nothing for MIS to weigh a light hit against")

    @classmethod
    def build(cls, **named) -> "EstimatorOptions":
        """Options from flat field names of the parts (``max_depth=3, nee_cos_light=False, ...``); the rest default."""
        parts: dict = {name: {} for name in PARTS}
        for key, value in named.items():
            part = _PART_OF.get(key)
            if part is None:
                raise ValueError(f"no estimator option {key!r} (have: {', '.join(_PART_OF)})")
            parts[part][key] = value
        return cls(**{name: PARTS[name](**values) for name, values in parts.items()})

    @property
    def depth_limit(self) -> int:
        """max_depth as the loop compares it: UNBOUNDED for -1, plus ``extra_depth`` otherwise."""
        s = self.settings
        return UNBOUNDED if s.max_depth == -1 else s.max_depth + self.mutations.extra_depth


#: Flat option name -> the part that holds it.
_PART_OF = {f.name: part for part, kind in PARTS.items() for f in fields(kind)}


#: Name -> default of every estimator trick the ``mcrt`` renderer takes (its Tricks, and Mutations' roulette scheme).
TRICK_OPTIONS = {"roulette": "unbiased", "roulette_survival": None, "roulette_start": None, "light_sampling": "area",
                 "sample_clamp": None, "bounce": "cosine", "bounce_at": "every", "mirror": "reflect",
                 "mirror_at": "every", "mirror_normal_length": 1.0, "pixel_statistic": "mean"}


def trick_options(tricks: dict) -> tuple:
    """The tricks that differ from their defaults, as sorted (name, value) pairs (hashable, for a tracer's cache)."""
    unknown = sorted(set(tricks) - set(TRICK_OPTIONS))
    if unknown:
        raise ValueError(f"no trick option {unknown[0]!r} (have: {', '.join(TRICK_OPTIONS)})")
    return tuple(sorted((k, v) for k, v in tricks.items() if v != TRICK_OPTIONS[k]))
