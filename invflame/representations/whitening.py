r"""Noise weighting of the data term: :math:`\sum ((F(\theta) - d) / \sigma)^2`.

With independent Gaussian noise of standard deviation :math:`\sigma` per measured value, the
whitened misfit is the negative log-likelihood up to constants, and at a solution that fits the
data to the noise it is close to the number of measurements :math:`M` (its expectation is
:math:`M` for the true fields, with standard deviation :math:`\sqrt{2M}`).

A value with :math:`\sigma = \infty` (a masked pixel or wavenumber of a measurement file,
:mod:`invflame.measurement_file`) has weight 0: it drops out of the data term.
"""

from __future__ import annotations

import numpy as np

import operators as op


def noise_weights(sigma, data_shape) -> np.ndarray | None:
    """``1 / sigma`` broadcast to ``data_shape`` (1/(W/(m²·sr·cm⁻¹))), or None for ``sigma``
    None.

    Parameters
    ----------
    sigma : float or array_like, optional
        Noise standard deviation in W/(m²·sr·cm⁻¹): a scalar, per wavenumber ``(n_out,)`` or
        per value ``data_shape``; all positive, ``inf`` for a masked value (weight 0).
    data_shape : tuple of int
        ``(n_rays, n_out)``.
    """
    if sigma is None:
        return None
    sigma = np.asarray(sigma, dtype=np.float64)
    try:
        sigma = np.broadcast_to(sigma, data_shape)
    except ValueError:
        raise ValueError(f"sigma of shape {sigma.shape} does not broadcast to the data shape "
                         f"{tuple(data_shape)}; give a scalar, one value per wavenumber or "
                         "one per measured value") from None
    if not np.all(sigma > 0):  # NaN fails too; inf is a masked value
        raise ValueError("sigma (noise standard deviation, W/(m2 sr cm-1)) must be finite and "
                         "positive everywhere, or inf for a masked value (weight 0)")
    return 1.0 / sigma


def whitened(forward: op.Operator, data, sigma) -> tuple[op.Operator, np.ndarray]:
    """``(diag(1/σ) @ forward, data / σ)``: a plain sum of squares of these is the whitened
    misfit; unchanged for ``sigma`` None.

    Parameters
    ----------
    forward : operators.Operator
        Map to data of shape ``forward.dimsd`` (W/(m²·sr·cm⁻¹)).
    data : array_like
        Measured data, ``forward.dimsd``.
    sigma : float or array_like, optional
        See :func:`noise_weights`.
    """
    data = np.asarray(data)
    weights = noise_weights(sigma, forward.dimsd)
    if weights is None:
        return forward, data
    if data.size != weights.size:
        raise ValueError(f"data of shape {data.shape} does not match the forward map's "
                         f"{tuple(forward.dimsd)}")
    scaled = (data.reshape(forward.dimsd) * weights).astype(forward.dtype)
    return op.Diagonal(weights, dtype=forward.dtype, name="whiten") @ forward, scaled
