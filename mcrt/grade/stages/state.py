"""What the stages of grading share: the hand-in being graded and what they record for the feedback."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mcrt.grade.expected import Context
from mcrt.grade.scoring import Rubric, StudentResult, image_items
from mcrt.stats.onesample import Noise


class Grading:
    """One hand-in being graded: the context, the rubric, and the notes, details, figures and diagnosis."""

    def __init__(self, ctx: Context, student: str):
        self.ctx0 = ctx
        self.ctx = ctx  # coarsened to the hand-in's grade resolution by the formats stage
        self.a = ctx.assignment
        self.th = self.a.thresholds
        self.student = student
        self.rubric = Rubric(image_items(self.a))
        self.notes: list[str] = []
        self.details: dict = {}
        self.figures: dict = {}
        self.diagnosis: list[dict] = []
        self.headline = ""
        self.chi0 = 0.0  # chi^2 of 'no bug' of the last catalogue ranking
        self.encoding = "linear"
        self.corrected: list[str] = []
        self.explanation = None  # mcrt.grade.candidates.Explanation, when the image was explained
        # Decode the file as its format and manifest declare, whatever curve fits best: the grader's second reading
        # of a hand-in whose first was explained by values moved (calibration.read_as_declared).
        self.as_declared = False

    def result(self) -> StudentResult:
        return self.rubric.result(self.student, headline=self.headline, notes=self.notes, diagnosis=self.diagnosis,
                                  details=self.details, figures=self.figures)


@dataclass
class Hand:
    """The hand-in's images as the stages pass them on (grade resolution once the formats stage is done)."""

    loaded: object  # mcrt.grade.checks.Loaded: the files as read
    spp: int | None  # declared samples per pixel (manifest or file)
    plan: object = None  # mcrt.grade.checks.ResolutionPlan
    imgs: list[np.ndarray] = field(default_factory=list)  # one or two renders, box-filtered to the grade resolution
    qvar: list[np.ndarray] = field(default_factory=list)  # their quantisation variances
    mask: np.ndarray | None = None  # (H, W) finite pixels
    cam: str = ""  # the camera the image shows
    ref: object = None  # that camera's reference (Expected)
    R: np.ndarray | None = None  # its mean, float64
    diag_imgs: list[np.ndarray] = field(default_factory=list)  # the images after flips only (for the catalogue)
    transform: str = "identity"  # the flip or rotation undone
    png_safe: np.ndarray | None = None  # display images: pixels an 8-bit file cannot have clipped
    base_tile: int = 8  # the bias test's first tile size
    corrected: list[str] = field(default_factory=list)  # what the calibration stage undid

    @property
    def n_r(self) -> int:
        return len(self.imgs)

    @property
    def k_down(self) -> int:
        return self.plan.down


@dataclass
class Level:
    """The measured noise and the noise model of the tests."""

    img: np.ndarray  # the graded image (the mean of two renders)
    q: np.ndarray  # its quantisation variance
    pair: np.ndarray | None  # (a - b)^2 / 4 of two renders
    resid: np.ndarray  # img - R on the finite pixels
    clip_mask: np.ndarray  # the pixels every statistic uses
    model_ps: np.ndarray  # mcrt's per-sample variance at the grade resolution
    ref_noise: np.ndarray  # the reference's variance of its mean
    per: int  # hand-in renders x pixels per grade pixel
    spp_eff: float  # the samples per pixel the noise suggests
    var_ratio: float  # the noise over mcrt's at the declared (or minimum) spp
    spp_nominal: int  # what the noise is judged against
    spp_model: int  # what the noise model assumes
    verdict: tuple[str, str, bool]  # (status, text, firm) before the bias test is known
    noise: Noise | None = None
    spp_broad: float = float("inf")  # spp_eff with the noisiest tiles left out (stages.noise.BIAS_TILES)
    spp_away: float = float("inf")  # spp_eff away from the light's edges (stages.noise.measure)
    spp_smooth: float = float("inf")  # spp_eff away from every sharp edge (stages.noise.sharp_edges)
    smooth: np.ndarray | None = None  # (H, W) the pixels away from the light's and every sharp edge it is measured on
    edge_excess: bool = False  # the excess noise lies on the light's outline alone (stages.noise.edge_text)
    # The noise is shaped like a tracer's without light sampling (stages.noise.unsampled_shape): model_ps is that
    # tracer's, and this is how many times noisier it is than mcrt's at the same spp.
    unsampled: float = 0.0

    @property
    def samples(self) -> int:
        return self.spp_model * self.per
