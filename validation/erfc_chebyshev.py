"""The Chebyshev coefficients of the compiled normal tail (``fsrbayes.inference.count_kernels``).

For a ≥ 0, t = 2/(2 + a) and y = 2t − 1 ∈ (−1, 1],

    erfc(a) = t·exp(−a² + g(y)),   g(y) = log(erfc(a)/t) + a² = Σ_j c_j T_j(y),

the form of Numerical Recipes' ``erfccheb``. This script interpolates g at ``N`` Chebyshev nodes
with 50 significant digits (mpmath: ``pip install mpmath``), prints the coefficients down to
those below 1e-18 (c₀ … c₃₀), and checks them against ``ERFC_CHEBYSHEV``.

Run ``python -m validation.erfc_chebyshev``.
"""

N = 80
"""Interpolation nodes; the coefficients past ~40 are below 1e-23, so 80 leave no aliasing."""

KEPT = 31
"""Coefficients kept: the first left out, c₃₁, is below 1e-19."""


def chebyshev_coefficients(n=N, digits=50):
    """Return the first ``n`` coefficients c_j of g, as mpmath numbers."""
    import mpmath as mp

    mp.mp.dps = digits

    def g(y):
        t = (y + 1) / 2
        a = 2 / t - 2
        return mp.log(mp.erfc(a) / t) + a * a

    angles = [mp.pi * (k + mp.mpf(1) / 2) / n for k in range(n)]
    values = [g(mp.cos(angle)) for angle in angles]
    coefficients = [
        2 * mp.fsum(v * mp.cos(j * angle) for v, angle in zip(values, angles, strict=True)) / n
        for j in range(n)
    ]
    coefficients[0] /= 2
    return coefficients


def main():
    from fsrbayes.inference.count_kernels import ERFC_CHEBYSHEV

    coefficients = chebyshev_coefficients()
    for j, c in enumerate(coefficients[:KEPT]):
        print(f"c{j:<2d} {float(c)!r}")
    print(f"largest left out: {max(abs(float(c)) for c in coefficients[KEPT:]):.1e}")
    same = all(float(c) == k for c, k in zip(coefficients[:KEPT], ERFC_CHEBYSHEV, strict=True))
    print("ERFC_CHEBYSHEV", "matches" if same else "DIFFERS")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())
