"""Per-lane random numbers: a Weyl sequence through an integer mixer, 32 bits wide.

Each lane holds a 32-bit counter s and an odd 32-bit increment g, and draw k
(k = 1, 2, ...) is

    x_k = mix(s + k g)  (mod 2^32),    u_k = floor(x_k / 2^9) / 2^23  in [0, 1),

with ``mix`` a 32-bit avalanche hash (two rounds of xor-shift and multiply,
constants from Wellons' hash-prospector search, chosen there for their low
bias: flipping one input bit flips each output bit with probability close to
one half).

Seeding: lane i of a pass with 32-bit keys (k0, k1) starts at
s = mix(i ^ k0), a bijection of the lane index, so no two lanes of a pass
start alike, and steps by g = mix(s + k1) | 1. Each lane has its own
increment, so two lanes' sequences never run in step: with one shared
increment a lane that started j steps behind another would repeat its
numbers. A lane draws a few hundred numbers in a pass (its paths, up to 16
of a few dozen numbers each), far below the period 2^32.

Why not Dr.Jit's PCG32, which mcrt used before: seeded with consecutive
stream indices (``initseq + lane``), consecutive lanes, the samples of one
pixel, come out correlated (their sums do not vary as independent samples'
do), which breaks every per-pixel variance estimate. It is also dearer: its
64-bit state and increment fill four AVX-512 registers per 16 lanes and a
draw costs two 64-bit multiplies; this generator keeps one register of state
and draws with a few 32-bit operations, which leaves the path kernel more
registers and fewer instructions per draw (``mcrt bench --profile`` times
the draws alone). tests/test_rng.py checks it
against a NumPy twin bit for bit and tests uniformity, successive draws,
second differences and blocks of lanes; every comparison with Mitsuba tests
it end to end.
"""

from __future__ import annotations

import drjit as dr

MIX_1 = 0x21F0AAAD
MIX_2 = 0x735A2D97
FLOAT_ONE_BITS = 0x3F800000  # 1.0f: 23 random mantissa bits under it give [1, 2)


def mix32(x):
    """32-bit avalanche hash; the same code runs on Dr.Jit UInt32 and NumPy uint32 arrays."""
    x = x ^ (x >> 16)
    x = x * MIX_1
    x = x ^ (x >> 15)
    x = x * MIX_2
    return x ^ (x >> 15)


class WeylRng:
    """One random stream per lane; ``next_1d()`` draws u in [0, 1) on every lane (the name of Mitsuba's samplers' draw, so the estimator takes either).

    Only ``state`` changes; inside a symbolic loop Dr.Jit carries it as loop
    state (the struct is traversed through ``DRJIT_STRUCT``) and drops the
    unchanging ``step``.
    """

    DRJIT_STRUCT = {"state": object, "step": object}

    def __init__(self, state=None, step=None):
        self.state, self.step = state, step  # Dr.Jit also builds empty instances when it copies state

    @classmethod
    def seeded(cls, m, lanes: int, key0, key1) -> WeylRng:
        """``lanes`` streams of backend ``m`` keyed by two UInt32 keys (opaque keys: new ones do not recompile)."""
        state = mix32(dr.arange(m.UInt32, lanes) ^ key0)
        return cls(state, mix32(state + key1) | 1)

    def next_uint32(self):
        self.state = self.state + self.step
        return mix32(self.state)

    def next_1d(self):
        bits = (self.next_uint32() >> 9) | FLOAT_ONE_BITS
        return dr.reinterpret_array(dr.float32_array_t(type(bits)), bits) - 1.0


#: Golden-ratio multiplier (odd) that spreads consecutive sample indices over the 32-bit keys.
SAMPLE_MULT = 0x9E3779B9


class SampleStreams(WeylRng):
    """Lanes whose random stream is that of one pixel sample: a function of (keys, pixel, sample) alone.

    The stream of sample s of pixel p is the Weyl sequence above with

        s_0 = mix(h0 + s G),    g = mix(h1 + s G) | 1,    h0 = mix(p ^ k0),  h1 = mix(p ^ k1),

    G = SAMPLE_MULT. For a fixed sample, p -> s_0 is a bijection (no two
    pixels start alike), and for a fixed pixel so is s -> s_0; the
    increment differs too, so two samples' sequences do not run in step.
    Which lane, launch or tile traces a sample does not enter: a render is
    the same whatever its tiling. :meth:`restart` moves the lanes of a mask
    on to their next sample (``sample`` + 1) and reseeds them.
    """

    DRJIT_STRUCT = {"state": object, "step": object, "sample": object, "h0": object, "h1": object}

    def __init__(self, state=None, step=None, sample=None, h0=None, h1=None):
        super().__init__(state, step)
        self.sample, self.h0, self.h1 = sample, h0, h1

    @classmethod
    def start(cls, pixel, sample, key0, key1) -> SampleStreams:
        """Streams of ``sample`` (UInt32 per lane) of ``pixel`` (UInt32 per lane) under the keys (opaque UInt32)."""
        h0, h1 = mix32(pixel ^ key0), mix32(pixel ^ key1)
        state, step = cls._seed(h0, h1, sample)
        return cls(state, step, sample, h0, h1)

    @staticmethod
    def _seed(h0, h1, sample):
        return mix32(h0 + sample * SAMPLE_MULT), mix32(h1 + sample * SAMPLE_MULT) | 1

    def restart(self, mask) -> None:
        """Where ``mask``: the lane's next sample, its stream from the start."""
        sample = self.sample + 1
        state, step = self._seed(self.h0, self.h1, sample)
        self.state = dr.select(mask, state, self.state)
        self.step = dr.select(mask, step, self.step)
        self.sample = dr.select(mask, sample, self.sample)
