// SPDX-License-Identifier: Apache-2.0
/// @file TestWinklerBeam.cpp
/// @brief The bending needle's beam against closed forms (physics.md §9.2, §9.4,
/// §7 R8): the band solve against Eigen's dense one, a cantilever under an end
/// load (δ = FL³/3EI), a beam on a uniform Winkler foundation under an end load
/// (Hetényi's semi-infinite form with λL ≥ 6, and the finite free–free form), a
/// propped cantilever (the end pinned).
/// Each with a control where the rule it checks does not hold.

#include "core/Errors.h"
#include "haptic/beam/BandedCholesky.h"
#include "haptic/beam/WinklerBeam.h"

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace voxhap::haptic {
namespace {

/// Round-off of a band solve of a few hundred unknowns with condition numbers
/// up to ~1e8 (EI/h³ against k·h): ~1e-16·1e8 relative, with headroom.
constexpr double kSolveRelative = 1e-7;

/// Hermite elements reproduce a cantilever's nodal deflections under end loads
/// exactly (the true solution is cubic): only round-off remains, amplified by the
/// stiffness matrix's condition number, which grows as n⁴ with n elements:
/// 80⁴·1e-16 ≈ 4e-9.
constexpr double kCantileverRelative = 1e-8;

/// The finite element error of the foundation's term: the consistent matrix with
/// four-point quadrature is exact for a cubic deflection, and the true one is
/// e^(−λx)·cos λx, which a cubic follows over an element to O((λh)⁴) relative.
/// The tests take λh ≤ 0.1: (λh)⁴ ≤ 1e-4, times 3 for headroom.
inline double discretisation(double lambdaH) { return 3.0 * std::pow(lambdaH, 4); }

/// A 22 G needle with its stylet (physics.md §9.1): EI = 193 GPa · π·0.718⁴/64.
const double kEi = 193e3 * 3.14159265358979323846 * std::pow(0.718, 4) / 64.0;

TEST(BandedCholesky, SolvesAsEigenDenseDoesAndRefusesAnIndefiniteMatrix)
{
    constexpr int B = 3, n = 60;
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i)
        for (int j = std::max(0, i - B); j < i; ++j) a(i, j) = a(j, i) = u(rng);
    for (int i = 0; i < n; ++i) a(i, i) = 2.0 * B + 1.0 + u(rng); // diagonally dominant: positive definite
    std::vector<double> band(std::size_t(n * (B + 1)), 0.0);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j <= std::min(i, B); ++j) band[std::size_t(i * (B + 1) + j)] = a(i, i - j);
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) b(i) = u(rng);
    const Eigen::VectorXd expected = a.llt().solve(b);
    ASSERT_TRUE(choleskyBand<B>(band.data(), n));
    std::vector<double> x(b.data(), b.data() + n);
    solveBand<B>(band.data(), n, x.data());
    for (int i = 0; i < n; ++i) EXPECT_NEAR(x[std::size_t(i)], expected(i), kSolveRelative * expected.norm()) << i;

    // Control: an indefinite matrix (one negative pivot) is refused, not solved.
    std::vector<double> bad(std::size_t(n * (B + 1)), 0.0);
    for (int i = 0; i < n; ++i) bad[std::size_t(i * (B + 1))] = i == n / 2 ? -1.0 : 1.0;
    EXPECT_FALSE(choleskyBand<B>(bad.data(), n));
}

TEST(WinklerBeam, CantileverUnderAnEndLoadDeflectsFL3Over3EI)
{
    const double L = 80.0, f1 = 0.3, f2 = -0.12;
    for (const int elements : {1, 7, 80}) {
        WinklerBeam beam(elements, L, kEi, /*clampedStart=*/true);
        beam.begin();
        beam.addEndForce(f1, f2);
        ASSERT_TRUE(beam.solve());
        const int tip = elements;
        EXPECT_NEAR(beam.deflection(tip, 0), f1 * L * L * L / (3.0 * kEi),
            kCantileverRelative * std::abs(f1) * L * L * L / kEi);
        EXPECT_NEAR(beam.deflection(tip, 1), f2 * L * L * L / (3.0 * kEi),
            kCantileverRelative * std::abs(f2) * L * L * L / kEi);
        EXPECT_NEAR(beam.slope(tip, 0), f1 * L * L / (2.0 * kEi), kCantileverRelative * std::abs(f1) * L * L / kEi);
        // Mid-span: δ(x) = F·x²·(3L − x)/(6EI).
        const double x = 0.5 * L;
        double w1 = 0.0, w2 = 0.0;
        beam.deflectionAt(x, w1, w2);
        EXPECT_NEAR(w1, f1 * x * x * (3.0 * L - x) / (6.0 * kEi), kCantileverRelative * std::abs(f1) * L * L * L / kEi);
        // The clamp holds the load: a force −F and a moment −F·L.
        double r1 = 0.0, r2 = 0.0, m1 = 0.0, m2 = 0.0;
        beam.startReaction(r1, r2, m1, m2);
        EXPECT_NEAR(r1, -f1, 1e-9);
        EXPECT_NEAR(r2, -f2, 1e-9);
        EXPECT_NEAR(m1, -f1 * L, 1e-9 * L);
        EXPECT_NEAR(m2, -f2 * L, 1e-9 * L);
    }
    // Control: a beam whose start is not clamped has no cantilever: without a
    // foundation its matrix is singular, and the solve says so.
    WinklerBeam free(10, L, kEi, /*clampedStart=*/false);
    free.begin();
    free.addEndForce(f1, f2);
    EXPECT_FALSE(free.solve());
}

// A propped cantilever (physics.md §9.5, bone pinning the tip): the end held at δ
// across the beam, its slope free. Closed form: w(x) = δ·x²·(3L − x)/(2L³), the
// end's slope 3δ/(2L), the pin's force 3EI·δ/L³, which the clamp holds with a
// moment of that force times L; a cubic, which Hermite elements reproduce exactly.
TEST(WinklerBeam, PinnedEndIsAProppedCantilever)
{
    const double L = 60.0, d1 = 1.5, d2 = -0.4;
    for (const int elements : {1, 6, 60}) {
        WinklerBeam beam(elements, L, kEi, /*clampedStart=*/true);
        beam.begin();
        beam.addEndForce(0.7, 0.7); // a load at a pinned end goes into the pin
        beam.pinEnd(d1, d2);
        ASSERT_TRUE(beam.solve());
        const double tol = kCantileverRelative * std::abs(d1);
        EXPECT_NEAR(beam.deflection(elements, 0), d1, tol);
        EXPECT_NEAR(beam.deflection(elements, 1), d2, tol);
        EXPECT_NEAR(beam.slope(elements, 0), 1.5 * d1 / L, tol / L);
        double w1 = 0.0, w2 = 0.0;
        const double x = L / 3.0;
        beam.deflectionAt(x, w1, w2);
        EXPECT_NEAR(w1, d1 * x * x * (3.0 * L - x) / (2.0 * L * L * L), tol);
        double r1 = 0.0, r2 = 0.0, m1 = 0.0, m2 = 0.0;
        beam.startReaction(r1, r2, m1, m2);
        const double pin = 3.0 * kEi * d1 / (L * L * L);
        EXPECT_NEAR(r1, -pin, 1e-7 * std::abs(pin)) << elements;
        EXPECT_NEAR(m1, -pin * L, 1e-7 * std::abs(pin) * L) << elements;
        // The clamp moved sideways with the pinned end held: the same propped
        // cantilever, 3EI/L³ per millimetre.
        EXPECT_NEAR(beam.startTranslationStiffness(), 3.0 * kEi / (L * L * L), 1e-7 * kEi / (L * L * L)) << elements;
    }
    // Control: without the pin the unloaded beam stays on its axis.
    WinklerBeam beam(6, L, kEi, /*clampedStart=*/true);
    beam.begin();
    ASSERT_TRUE(beam.solve());
    EXPECT_EQ(beam.deflection(6, 0), 0.0);
}

/// Hetényi: a long beam on a Winkler foundation k under an end load P deflects
/// y(0) = 2Pλ/k at the loaded end, λ = (k/4EI)^¼, with slope −2Pλ²/k (into the beam).
struct Hetenyi {
    double k, lambda;
    explicit Hetenyi(double kNPerMm2) : k(kNPerMm2), lambda(std::pow(kNPerMm2 / (4.0 * kEi), 0.25)) { }
    double endDeflection(double p) const { return 2.0 * p * lambda / k; }
};

/// A beam of @p length on k over its whole length, end load @p p at x = L.
double loadedEnd(double k, double length, double p, bool clamped, int elements)
{
    WinklerBeam beam(elements, length, kEi, clamped);
    beam.begin();
    beam.addFoundation(0.0, [k](double, double& kk, double& r1, double& r2) { kk = k, r1 = r2 = 0.0; });
    beam.addEndForce(p, 0.0);
    EXPECT_TRUE(beam.solve());
    return beam.deflection(elements, 0);
}

TEST(WinklerBeam, SemiInfiniteWinklerEndDeflectionIs2PLambdaOverK)
{
    const double p = 0.2;
    for (const double k : {0.5, 1.0, 4.0}) {
        const Hetenyi h(k);
        // λL ≥ 6, where a finite beam differs from the semi-infinite one by less
        // than e^(−λL) (2.8e-5 relative at λL = 6 for a clamped far end, by the
        // continuum solution; e^(−6) = 2.5e-3 bounds it).
        const double length = 8.0 / h.lambda;
        const int elements = int(std::ceil(length * h.lambda / 0.1)); // λh ≤ 0.1
        const double got = loadedEnd(k, length, p, true, elements);
        const double tol = std::exp(-h.lambda * length) + discretisation(h.lambda * length / elements);
        EXPECT_NEAR(got, h.endDeflection(p), tol * h.endDeflection(p)) << "k = " << k;
    }
    // Control: at λL = 1 the beam is short, the clamp holds the load, and the
    // semi-infinite form is 49 % off: the same comparison fails.
    const Hetenyi h(1.0);
    const double length = 1.0 / h.lambda;
    const double got = loadedEnd(1.0, length, p, true, 40);
    EXPECT_GT(std::abs(got - h.endDeflection(p)), 0.4 * h.endDeflection(p));
}

TEST(WinklerBeam, FiniteFreeFreeBeamMatchesItsClosedForm)
{
    // y(0) = (2Pλ/k)·(sinh λL·cosh λL − sin λL·cos λL)/(sinh²λL − sin²λL), for any λL.
    const double p = 0.2, k = 1.0;
    const Hetenyi h(k);
    for (const double lambdaL : {1.0, 2.0, 3.0}) {
        const double length = lambdaL / h.lambda;
        const int elements = int(std::ceil(lambdaL / 0.05));
        const double x = lambdaL;
        const double form = h.endDeflection(p) * (std::sinh(x) * std::cosh(x) - std::sin(x) * std::cos(x)) /
            (std::sinh(x) * std::sinh(x) - std::sin(x) * std::sin(x));
        const double got = loadedEnd(k, length, p, false, elements);
        EXPECT_NEAR(got, form, discretisation(0.05) * form) << "λL = " << lambdaL;
        // Control: at these lengths the semi-infinite form is 2–100 % off (the free
        // far end lets the whole beam sink), so it would fail the same tolerance.
        if (lambdaL <= 2.0) {
            EXPECT_GT(std::abs(got - h.endDeflection(p)), 0.1 * form);
        }
    }
}

// The hub's lateral stiffness (§9.5): the clamped start translated, its slope held.
// In air the needle moves as a whole: no force. On a long Winkler beam, Hetényi's
// semi-infinite beam with a guided end (y' = 0) under P: y(0) = Pλ/k, so K = k/λ = 4EIλ³.
TEST(WinklerBeam, ClampedStartTranslationStiffness)
{
    const double L = 60.0;
    for (const int elements : {1, 6, 60}) {
        WinklerBeam beam(elements, L, kEi, /*clampedStart=*/true);
        beam.begin();
        ASSERT_TRUE(beam.solve());
        // A rigid translation: zero to round-off of the band solve (K's terms are EI/h³).
        const double scale = 12.0 * kEi * std::pow(elements / L, 3);
        EXPECT_NEAR(beam.startTranslationStiffness(), 0.0, kSolveRelative * scale) << elements;
    }
    for (const double k : {0.1, 1.0}) {
        const Hetenyi h(k);
        const double length = 8.0 / h.lambda;
        const int elements = int(std::ceil(length * h.lambda / 0.1));
        WinklerBeam beam(elements, length, kEi, /*clampedStart=*/true);
        beam.begin();
        beam.addFoundation(0.0, [k](double, double& kk, double& r1, double& r2) { kk = k, r1 = r2 = 0.0; });
        ASSERT_TRUE(beam.solve());
        const double form = k / h.lambda;
        const double tol = std::exp(-h.lambda * length) + discretisation(h.lambda * length / elements);
        EXPECT_NEAR(beam.startTranslationStiffness(), form, tol * form) << "k = " << k;
        // Control: the free end's stiffness k/(2λ) (y(0) = 2Pλ/k) is half: the test
        // tells a guided start from a free one.
        EXPECT_GT(std::abs(form - k / (2.0 * h.lambda)), 10.0 * tol * form);
    }
    // A free start has no clamp to translate; an unsolved load case has no factor.
    WinklerBeam free(10, L, kEi, /*clampedStart=*/false);
    free.begin();
    EXPECT_EQ(free.startTranslationStiffness(), 0.0);
    WinklerBeam unsolved(10, L, kEi, /*clampedStart=*/true);
    unsolved.begin();
    EXPECT_EQ(unsolved.startTranslationStiffness(), 0.0);
}

TEST(WinklerBeam, RefusesABeamWithoutLengthOrStiffness)
{
    EXPECT_THROW(WinklerBeam(0, 10.0, kEi, true), ValueError);
    EXPECT_THROW(WinklerBeam(4, 0.0, kEi, true), ValueError);
    EXPECT_THROW(WinklerBeam(4, 10.0, -1.0, true), ValueError);
    EXPECT_THROW(WinklerBeam(4, 10.0, std::nan(""), true), ValueError);
}

} // namespace
} // namespace voxhap::haptic
