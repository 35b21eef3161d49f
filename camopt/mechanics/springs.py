"""Helical compression springs (Shigley, 3rd ed., pp 295-308, as used by Clauss 1982)."""

from __future__ import annotations

from camopt.mechanics import FloatsLike


def helical_rate(wire_d: FloatsLike, coil_d: FloatsLike, shear_modulus: FloatsLike,
                 coils: FloatsLike) -> FloatsLike:
    """Spring rate k = d^4 G / (8 D^3 N) in N/m (Clauss Eq 21, R13)."""
    return wire_d**4 * shear_modulus / (8.0 * coil_d**3 * coils)


def stress_correction(wire_d: FloatsLike, coil_d: FloatsLike) -> FloatsLike:
    """Direct-shear correction Ks = 1 + 0.5 d/D (Clauss's 'Wahl' K; Nomenclature)."""
    return 1.0 + 0.5 * wire_d / coil_d


def strength_ratio(rate: FloatsLike, deflection: FloatsLike, wire_d: FloatsLike,
                   coil_d: FloatsLike, strength_a: FloatsLike, exponent: FloatsLike,
                   d_for_strength: FloatsLike | None = None) -> FloatsLike:
    """Shear-strength use Ks D k delta / (0.17 A d^(3-m)) (Clauss Eq 22, R14); <= 1 is safe.

    ``d_for_strength`` is d in the unit the strength law A d^-m was fitted in
    (defaults to ``wire_d``); the d^3 of the stress formula stays in metres.
    """
    d_strength = wire_d if d_for_strength is None else d_for_strength
    allowable = 0.17 * strength_a * wire_d**3 * d_strength ** (-exponent)
    return stress_correction(wire_d, coil_d) * coil_d * rate * deflection / allowable


def max_deflection(rate: FloatsLike, wire_d: FloatsLike, coil_d: FloatsLike,
                   strength_a: FloatsLike, exponent: FloatsLike,
                   d_for_strength: FloatsLike | None = None) -> FloatsLike:
    """Deflection at which :func:`strength_ratio` reaches 1 (Clauss Eq 82 with R14 active)."""
    return 1.0 / strength_ratio(rate, 1.0, wire_d, coil_d, strength_a, exponent, d_for_strength)
