r"""Pixel samplers: where in its pixel each camera sample lands, and how the render's variance is then estimated.

``independent`` (the default): the jitter (u, v) of sample s of pixel p is
the first two numbers of that sample's own random stream
(:class:`mcrt.rng.SampleStreams`). Samples are independent, so a pixel's
per-sample spread estimates its variance with spp - 1 degrees of freedom.

``sobol``: randomised quasi-Monte Carlo in R independent replicates. The spp
samples of a pixel are R runs of N = spp / R; sample s is point i = s mod N
of replicate r = s div N. The jitter of point i is the i-th point of the
two-dimensional Sobol sequence (van der Corput in u, Sobol's second
dimension in v: a (0, 2)-sequence, so the first 2^m points put one point in
every elementary box of area 2^-m), Owen-scrambled with a seed drawn from
(seed, pixel, replicate). Owen scrambling keeps that stratification and
makes every point uniform on the pixel, so each replicate's mean is an
unbiased estimate; pixels and replicates are scrambled independently, so
the R replicate means of a pixel are independent and identically
distributed. Their spread is the honest variance: with M the overall mean
and m_r the replicate means,

.. math::

    \widehat{\mathrm{Var}}(M) = \frac{1}{R (R - 1)} \sum_r (m_r - M)^2 ,

with R - 1 degrees of freedom. The per-sample spread would overstate it
(the samples of a replicate are negatively correlated, which is the point).
A render stores ``spp`` times this as its "per-sample" variance, so that
variance / spp is Var(M) as for every other render, and says so in
``extra['variance_method'] = 'replicates:R'`` (an EXR header attribute
``mcrt.variance_method``); :func:`mcrt.stats.variance_dof` reads it and the
two-sample test gives that side R - 1 degrees of freedom per pixel.

Every renderer takes it: the standalone tracer sums replicates per tile
(:func:`replicate_launch`), the Mitsuba hosts (renderers ``plugin`` and
``mitsuba``) per whole-image pass (:func:`replicate_passes`), with the same
points at the same seed (:func:`mcrt.mitsuba_scene._sobol_jitter`).

The path's own dimensions (light samples, directions, roulette) stay on the
sample's random stream: only the pixel is stratified, which is where the
error of pixels partly covering the light sits (an edge's error falls as
N^-3/4 instead of N^-1/2 in the number of samples of a replicate).

The scrambling is the hash-based nested uniform scramble (Burley 2020,
"Practical Hash-based Owen Scrambling", after Laine and Karras 2011): on
the bit-reversed value, multiplications and additions carry each bit's
influence only towards more significant positions, so after reversing back
each bit is flipped by a function of the bits above it alone, which is
Owen's scrambling with hashed flip decisions. Written here for Dr.Jit's
UInt32 arrays (the kernel) and NumPy uint32 arrays (tests) alike, as
:func:`mcrt.rng.mix32` is.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mcrt.rng import mix32

#: The pixel samplers, by name (``render(..., pixel_sampler=...)``, ``mcrt render --pixel-sampler``).
PIXEL_SAMPLERS = {
    "independent": "each sample's jitter from its own random stream; variance from the samples (spp - 1 df)",
    "sobol": "Owen-scrambled Sobol points in R independent replicates; variance from the replicates (R - 1 df)",
}
#: Replicates of a ``sobol`` render unless told otherwise.
DEFAULT_REPLICATES = 8
#: The header value of renders whose variance is the spread of independent samples (files without one read so).
PER_SAMPLE = "samples"

_SCRAMBLE_SALT = 0x5BD1E995  # keeps the scramble seeds apart from the random streams' (both hash the pixel keys)
_SEED_U, _SEED_V = 0x68E31DA4, 0xB5297A4D


@dataclass(frozen=True)
class PixelSampler:
    """A pixel sampler and its replicates, checked; hashable (it keys the tracer cache)."""

    name: str = "independent"
    replicates: int = 1

    def __post_init__(self):
        if self.name not in PIXEL_SAMPLERS:
            raise ValueError(f"unknown pixel sampler {self.name!r} (one of {', '.join(PIXEL_SAMPLERS)})")
        if self.name == "independent" and self.replicates != 1:
            raise ValueError("replicates go with pixel sampler 'sobol' (independent samples estimate their own variance)")
        if self.name == "sobol" and self.replicates < 2:
            raise ValueError(f"pixel sampler 'sobol' needs at least 2 replicates for a variance, got {self.replicates}")

    @classmethod
    def of(cls, name: str = "independent", replicates: int | None = None) -> PixelSampler:
        """The sampler of the render options ``pixel_sampler`` and ``replicates`` (None: DEFAULT_REPLICATES for sobol)."""
        if name == "sobol":
            return cls(name, DEFAULT_REPLICATES if replicates is None else int(replicates))
        return cls(name, 1 if replicates is None else int(replicates))

    @property
    def default(self) -> bool:
        return self.name == "independent"

    def samples_per_replicate(self, spp: int) -> int:
        """N = spp / R, with a one-line ValueError where R does not divide spp."""
        if spp % self.replicates:
            raise ValueError(f"pixel sampler {self.name!r} with {self.replicates} replicates needs spp a multiple of "
                             f"{self.replicates}, got {spp}")
        return spp // self.replicates

    @property
    def variance_method(self) -> str:
        """The EXR header's ``variance_method``: 'samples', or 'replicates:R'."""
        return PER_SAMPLE if self.default else f"replicates:{self.replicates}"


# -- the points -------------------------------------------------------------------------------------------------


def _brev(x):
    """Bit reversal of 32-bit values (Dr.Jit's intrinsic on its arrays, shifts and masks on NumPy's)."""
    if isinstance(x, np.ndarray):
        x = x.astype(np.uint32)
        for shift, mask in ((1, 0x55555555), (2, 0x33333333), (4, 0x0F0F0F0F), (8, 0x00FF00FF)):
            x = ((x >> np.uint32(shift)) & np.uint32(mask)) | ((x & np.uint32(mask)) << np.uint32(shift))
        return (x >> np.uint32(16)) | (x << np.uint32(16))
    import drjit as dr

    return dr.brev(x)


def _u32(x, c: int):
    """The constant c in x's integer type (NumPy would widen a Python int beyond 32 bits)."""
    return np.uint32(c) if isinstance(x, np.ndarray) else c


def owen_scramble(x, seed):
    """Nested uniform (Owen) scramble of 32-bit fixed-point values ``x`` under ``seed`` (same array type).

    Bit k of the result is bit k of x flipped by a hash of (seed, the bits
    of x above k): an Owen scrambling with hashed decisions.
    """
    v = _brev(x)
    v = v ^ (v * _u32(v, 0x3D20ADEA))
    v = v + seed
    v = v * ((seed >> _u32(v, 16)) | _u32(v, 1))
    v = v ^ (v * _u32(v, 0x05526C56))
    v = v ^ (v * _u32(v, 0x53A22864))
    return _brev(v)


def _sobol_v_directions(bits: int) -> list[int]:
    """Sobol's second dimension, direction numbers for index bits 0 .. bits - 1 (primitive polynomial x + 1).

    Its generator matrix is Pascal's triangle mod 2: v_0 = 2^31, v_{k+1} = v_k xor (v_k >> 1).
    """
    v, out = 1 << 31, []
    for _ in range(bits):
        out.append(v)
        v ^= v >> 1
    return out


def sobol_02(index, bits: int):
    """The index-th point of the 2-D Sobol sequence as 32-bit fixed-point (u, v), for index < 2^bits.

    u is the van der Corput radical inverse (the bit-reversed index), v
    Sobol's second dimension. ``bits`` is a trace-time constant: the loop is
    unrolled over that many index bits.
    """
    u = _brev(index)
    numpy = isinstance(index, np.ndarray)
    v = np.zeros_like(index) if numpy else type(index)(0)
    for k, direction in enumerate(_sobol_v_directions(bits)):
        bit = (index >> _u32(index, k)) & _u32(index, 1)
        v = v ^ (bit * _u32(index, direction))  # bit is 0 or 1: a select without a mask
    return u, v


def _to_unit(x):
    """32-bit fixed point -> float32 in [0, 1): its top 24 bits, exactly representable."""
    if isinstance(x, np.ndarray):
        return (x >> np.uint32(8)).astype(np.float32) * np.float32(2.0**-24)
    import drjit as dr

    return dr.float32_array_t(type(x))(x >> 8) * (2.0**-24)


def scrambled_jitter(key, sample, samples_per_replicate: int):
    """Jitter (u, v) in [0, 1)^2 of ``sample`` (UInt32) of the pixel keyed by ``key`` (UInt32, seed and pixel).

    Sample s is point s mod N of replicate s div N (N =
    ``samples_per_replicate``, a trace-time constant); each (key, replicate)
    scrambles its own copy of the sequence, u and v with separate seeds.
    """
    n = int(samples_per_replicate)
    if n < 1:
        raise ValueError(f"samples per replicate must be >= 1, got {n}")
    pow2 = n & (n - 1) == 0
    index = sample & _u32(sample, n - 1) if pow2 else sample % _u32(sample, n)
    replicate = sample >> _u32(sample, n.bit_length() - 1) if pow2 else sample // _u32(sample, n)
    base = mix32(key ^ mix32(replicate ^ _u32(sample, _SCRAMBLE_SALT)))
    u, v = sobol_02(index, max(1, (n - 1).bit_length()))
    return (_to_unit(owen_scramble(u, mix32(base ^ _u32(base, _SEED_U)))),
            _to_unit(owen_scramble(v, mix32(base ^ _u32(base, _SEED_V)))))


# -- replicate sums -----------------------------------------------------------------------------------------------


def replicate_launch(launch, samples_per_replicate: int):
    """A tile launch (mcrt.film.run_tiles) whose sums are (sum of x, sum over replicates of S_r^2 / N).

    ``launch(acc, p0, count, first, n)`` as run_tiles calls it; every pass
    must lie inside one replicate (N a multiple of the pass size). S_r, a
    replicate's sum of x, is held until its last pass, then its square over
    N is added to the second sums. run_tiles' per-sample formula then
    gives N (R - 1) s^2 / (spp - 1), s^2 the replicate means' sample
    variance: :func:`replicate_variance_scale` turns it into spp Var(M).
    """
    n_rep = int(samples_per_replicate)
    held = {}

    def wrapped(acc, p0, count, first, n):
        if first // n_rep != (first + n - 1) // n_rep:
            raise ValueError(f"a pass of samples {first}..{first + n - 1} straddles replicates of {n_rep}")
        part = launch(held.get("part") if first % n_rep else None, p0, count, first, n)
        if (first + n) % n_rep:
            held["part"] = part
            return acc
        held.pop("part", None)
        s1 = part[0]
        s2 = tuple(v * v * (1.0 / n_rep) for v in s1)
        if acc is not None:
            s1, s2 = tuple(a + v for a, v in zip(acc[0], s1)), tuple(a + v for a, v in zip(acc[1], s2))
        import drjit as dr

        dr.eval(s1, s2)
        return s1, s2

    return wrapped


def replicate_passes(pass_sums, samples_per_replicate: int):
    """A pass function (mcrt.film.run_passes) whose sums are (sum of x, sum over replicates of S_r^2 / N).

    The whole-image twin of :func:`replicate_launch`, for the Mitsuba hosts'
    passes: ``pass_sums(k, n)`` returns a Float64 array laid out (moment,
    pixel, channel), and every pass has the same n, a divisor of N
    (:func:`replicate_pass_size`), so pass k holds samples k n .. k n + n - 1.
    A replicate's sums are held until its last pass; the passes before it
    add nothing.
    """
    import drjit as dr

    n_rep = int(samples_per_replicate)
    held = {}

    def wrapped(k: int, n: int):
        first = k * n
        if n_rep % n:
            raise ValueError(f"a pass of {n} samples does not divide replicates of {n_rep}")
        sums = pass_sums(k, n)
        part = sums if first % n_rep == 0 else held.pop("part") + sums
        Float64 = type(part)
        half = dr.width(part) // 2
        if (first + n) % n_rep:
            held["part"] = part
            return dr.zeros(Float64, 2 * half)
        idx = dr.arange(dr.uint32_array_t(Float64), half)
        s1 = dr.gather(Float64, part, idx)
        out = dr.zeros(Float64, 2 * half)
        dr.scatter(out, s1, idx)
        dr.scatter(out, s1 * s1 * (1.0 / n_rep), idx + half)
        dr.eval(out)
        return out

    return wrapped


def replicate_variance_scale(spp: int, replicates: int) -> float:
    """The factor (spp - 1) / (R - 1) from run_tiles' variance of replicate sums to spp Var(M) (see replicate_launch)."""
    return (spp - 1) / (replicates - 1)


def replicate_pass_size(per_pass: int, samples_per_replicate: int) -> int:
    """The largest pass size <= per_pass that divides N, so that no pass straddles two replicates."""
    size = max(1, min(per_pass, samples_per_replicate))
    while samples_per_replicate % size:
        size -= 1
    return size
