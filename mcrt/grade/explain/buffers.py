r"""Another of the film's buffers written for its mean: the samples' variance, or the mean of their squares.

A film that keeps its samples' sum and sum of squares (for a variance, an
adaptive sampler or a denoiser) can write the wrong one: with :math:`B` the
mean and :math:`\sigma^2` the per-sample variance of mcrt's render (the
basis's, one seed), the model images are

* the variance buffer: :math:`k\,\sigma^2` (zero where every sample agrees,
  as on the light; largest where a few paths find the light);
* the squares' buffer: :math:`k\,(\sigma^2 + B^2)` (the mean of the
  squared samples, the light's radiance squared).

k (one parameter, by weighted least squares) takes up a count the buffer
was divided by that is off by a little (n - 1 for n, a pass's count); a k
outside :data:`SCALES` is no candidate: far below 1 it fits any image near
black (a light below the floor), which is no buffer written. The basis's
variance is an estimate from its own samples, noisier than its mean: a
remainder of that noise makes a partial reading more likely than a claim,
which is the honest side.
"""

from __future__ import annotations

import numpy as np

from mcrt.grade.candidates import Candidate, Inputs
from mcrt.grade.explain.fit import Fit
from mcrt.grade.feedback import num as _num

#: The range of k a buffer written for the mean may take (the module docstring).
SCALES = (0.1, 10.0)
#: (name, what it is in words) of each buffer.
BUFFERS = (("variance", "the film's variance buffer written for its mean: each pixel the variance of its samples "
            "(zero where they all agree, as on the light)"),
           ("squares", "the mean of the samples' squares written for their mean (a buffer of squared samples): the "
            "light's radiance squared, every pixel its mean squared plus its samples' variance"))


def wrong_buffer(fit: Fit, inputs: Inputs) -> list[Candidate]:
    """Each buffer of :data:`BUFFERS` times its best k (the module docstring)."""
    b = inputs.basis
    var = np.maximum(b.var.astype(np.float64), 0.0)
    base = b.base.astype(np.float64)
    w = np.where(fit.ok, fit.w, 0.0)
    out = []
    for name, words in BUFFERS:
        img = var if name == "variance" else var + base * base
        den = float(np.sum(w * img * img))
        if den <= 0:
            continue
        k = float(np.sum(w * img * fit.S)) / den
        if not SCALES[0] <= k <= SCALES[1]:
            continue
        change = k * img - fit.R
        out.append(Candidate("wrong_buffer", f"{name} buffer", f"{words}, times {_num(k)}", fit.delta(change), 1,
                             value={"buffer": name, "scale": k}, change=change))
    return out


wrong_buffer.name = "wrong_buffer"
