r"""The per-segment weights of the emission kernel's sweeps (both implementations).

A segment's spectra are table rows (:mod:`operators.rte.tables`) times a few scalars: the
segment's block of rows (its temperature interval and composition block), the amounts of its
gas slots and soot, and its offset in the temperature interval (:mod:`operators.rte.kernel`,
module notes). JAX differentiates the weights; the sweeps carry the derivatives of the spectra.
"""

from __future__ import annotations

import jax.numpy as jnp

from operators.rte.blocks import composition_block, fraction_weights, n_composition_blocks
from operators.rte.tables import RTETables


def locate(tables: RTETables, temperature, fractions):
    """Each segment's block of table rows and its temperature interval (clamped to the end
    intervals); ``fractions`` as :func:`segment_weights` takes them."""
    nodes = tables.nodes
    interval = jnp.clip(jnp.searchsorted(nodes, temperature, side="right") - 1, 0,
                        nodes.shape[0] - 2)
    lowers = [fraction_weights(f, fractions[s], jnp)[0]
              for s, f in enumerate(tables.fraction_nodes) if len(f) > 1]
    blocks = n_composition_blocks(tables.fraction_nodes)
    return interval * blocks + composition_block(tables.fraction_nodes, lowers, jnp), interval


def segment_weights(tables: RTETables, interval, temperature, fractions, length):
    r"""The scalars per segment that the spectra depend on.

    For segments shaped ``s`` (``temperature`` in K, ``length`` in m, ``interval`` the
    temperature interval of :func:`locate`; ``fractions`` is ``(n_absorbing, *s)``, the soot
    volume fraction last when the tables have soot): the amounts ``(*s, n_slots [+ 1])``, per
    gas slot :math:`X_s \Delta s / T` (m/K; the table rows carry :math:`\sigma p 10^{-4}/k_B`),
    split as :math:`X_s (1 - w_s)` and :math:`X_s w_s` between the nodes either side of a
    species with several fraction nodes (:func:`operators.rte.blocks.fraction_weights`), and
    the soot's :math:`f_v \Delta s` (m); the offset :math:`u \in [0, 1]` in the temperature
    interval ``(*s,)``; and the temperature ``(*s,)`` in K, which the exact Planck law takes.
    """
    offset = (temperature - tables.nodes[interval]) * tables.inv_width[interval]
    per_length = length / temperature
    amount = []
    for s, nodes in enumerate(tables.fraction_nodes):
        gas = fractions[s] * per_length
        if len(nodes) > 1:
            weight = fraction_weights(nodes, fractions[s], jnp)[1]
            amount += [gas - gas * weight, gas * weight]
        else:
            amount.append(gas)
    if tables.soot:
        amount.append(fractions[-1] * length)
    return jnp.stack(amount, axis=-1), offset, temperature

