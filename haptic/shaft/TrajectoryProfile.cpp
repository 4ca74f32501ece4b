// SPDX-License-Identifier: Apache-2.0
/// @file TrajectoryProfile.cpp
/// @brief Cumulative integral along a locked line: build by exact traversal,
/// query in O(1), and the off-line error bound of TrajectoryProfile.h.

#include "haptic/shaft/TrajectoryProfile.h"

#include "core/Errors.h"
#include "haptic/shaft/detail/FieldReaders.h"

#include <optional>
#include <sstream>

namespace voxhap::haptic {

using detail::FloatGrid;
using detail::LabelGrid;

struct TrajectoryProfile::Impl {
    Impl(const MaterialField& field, double tolerance, double maxLength, bool trackLabels)
        : src(field, trackLabels, true, "trajectory profile"), labels(src.labels != nullptr), xform(src.xform)
    {
        src.box(0.0, lo, hi);
        const volume::Geometry g = volume::geometryOf(*xform);
        const double hMin = g.spacing.minCoeff();
        if (!(tolerance >= 0.0) || tolerance >= 0.5 * hMin) {
            throw ValueError("trajectory profile: tolerance must be in [0, half the smallest voxel size = " +
                std::to_string(0.5 * hMin) + " mm)");
        }
        if (!(maxLength > 0.0) || !std::isfinite(maxLength)) throw ValueError("trajectory profile: bad maximum length");
        // Rows of the world->index linear map: index displacement along axis a is row_a · world displacement.
        const Mat3d inv = (g.direction * g.spacing.asDiagonal()).inverse();
        for (int a = 0; a < 3; ++a) worldToIndexRow[a] = inv.row(a).transpose();
        // A line crosses at most sum_a L·|u_a|/h_a <= sqrt(3)·L/hMin faces, plus the two ends.
        maxRuns = std::size_t(std::ceil(std::sqrt(3.0) * maxLength / hMin)) + 8;
        bucketWidth = 0.5 * hMin;
        bucketsPerMm = 1.0 / bucketWidth;
        reserveAll(maxLength);
    }
    Impl(const Impl& o) = default;

    /// Capacity for the longest line, so that builds never allocate (a copied vector keeps only its size).
    void reserveAll(double maxLength)
    {
        const auto buckets = std::size_t(std::ceil(maxLength / bucketWidth)) + 2;
        start.reserve(maxRuns);
        after.reserve(maxRuns);
        cumulative.reserve(maxRuns + 1);
        value.reserve(maxRuns);
        label.reserve(maxRuns);
        bound.reserve(maxRuns + 1);
        bucketRun.reserve(buckets);
        if (labels) {
            cumLength.reserve((maxRuns + 1) * kMaxLabels);
            nextStart.reserve((maxRuns + 1) * kMaxLabels);
        }
    }

    void clear() noexcept
    {
        start.clear();
        after.clear();
        cumulative.clear();
        value.clear();
        label.clear();
        bound.clear();
        bucketRun.clear();
        cumLength.clear();
        nextStart.clear();
        slotOfLabel.fill(-1);
        slotCount = 0;
        locked = false;
    }

    /// Append a piece [s0, s1) of the line with value b and label l, and its bound contribution.
    void append(double s0, double s1, double b, int l, double boundPart) noexcept
    {
        if (!(s1 > s0)) return;
        if (!value.empty() && value.back() == b && label.back() == l) {
            bound.back() += boundPart; // merge equal neighbours into one run
            return;
        }
        start.push_back(s0);
        value.push_back(b);
        label.push_back(l);
        bound.push_back(boundPart);
        if (labels && slotOfLabel[std::size_t(l)] < 0) {
            labelOfSlot[std::size_t(slotCount)] = l;
            slotOfLabel[std::size_t(l)] = slotCount++;
        }
    }

    /// Largest |β(w) − β(v)| over the 26 neighbours w of voxel v.
    double span(const openvdb::Coord& v) noexcept
    {
        const double centre = src.betaReader->get(v);
        double m = 0.0;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    const float w = src.betaReader->get(v.offsetBy(dx, dy, dz));
                    if (std::isfinite(w)) m = std::max(m, std::abs(double(w) - centre));
                }
        return m;
    }

    /// Length of [sa, sb] where the line lies within the sideways reach of
    /// a face of voxel v (shifted frame: v spans [v, v+1] on each axis).
    double nearFaceLength(const openvdb::Coord& v, double sa, double sb) const noexcept
    {
        double m = 0.0;
        for (int a = 0; a < 3; ++a) {
            const double reach = reachIndex[a];
            if (reach <= 0.0) continue;
            for (double face : {double(v[a]), double(v[a]) + 1.0}) {
                if (rate[a] == 0.0) {
                    if (std::abs(originIndex[a] - face) < reach) m += sb - sa;
                    continue;
                }
                double s0 = (face - reach - originIndex[a]) / rate[a];
                double s1 = (face + reach - originIndex[a]) / rate[a];
                if (s0 > s1) std::swap(s0, s1);
                m += std::max(0.0, std::min(s1, sb) - std::max(s0, sa));
            }
        }
        return std::min(m, sb - sa);
    }

    bool build(const Vec3d& o, const Vec3d& dir, double maxLength, double tolerance) noexcept
    {
        clear();
        const double n = dir.norm();
        if (!(n > 0.0) || !std::isfinite(n) || !o.allFinite()) return false;
        origin = o;
        u = dir / n;
        const Segment line{o, o + maxLength * u};
        const detail::IndexSegment s = detail::toIndex(*xform, line, 0.5);
        if (!s.valid) return false;
        for (int a = 0; a < 3; ++a) {
            originIndex[a] = s.a[a];
            rate[a] = s.d[a] / maxLength; // index units per mm along the line
            // Largest index displacement along a for a world displacement ⊥ u of length δ.
            const Vec3d& r = worldToIndexRow[a];
            reachIndex[a] = tolerance * std::sqrt(std::max(0.0, r.squaredNorm() - std::pow(r.dot(u), 2)));
        }
        double t0 = 0.0, t1 = 0.0;
        if (detail::clip(s, lo, hi, t0, t1)) {
            append(0.0, t0 * maxLength, 0.0, 0, 0.0);
            detail::walkCells(s, t0, t1, [&](const openvdb::Coord& c, double ta, double tb) {
                const float bv = src.betaReader->get(c);
                const double b = std::isfinite(bv) ? double(bv) : 0.0;
                int l = src.labelReader ? src.labelReader->get(c) : 0;
                if (static_cast<unsigned>(l) >= static_cast<unsigned>(kMaxLabels)) l = 0;
                const double sa = ta * maxLength, sb = tb * maxLength;
                const double sp = span(c);
                append(sa, sb, b, l, sp > 0.0 ? sp * nearFaceLength(c, sa, sb) : 0.0);
            });
            append(t1 * maxLength, maxLength, 0.0, 0, 0.0);
        } else {
            append(0.0, maxLength, 0.0, 0, 0.0);
        }
        finish(maxLength);
        locked = true;
        return true;
    }

    /// Cumulative sums, per-label tables and the bucket index.
    void finish(double maxLength) noexcept
    {
        const std::size_t runs = start.size();
        cumulative.assign(1, 0.0);
        double b = 0.0;
        std::vector<double>& cb = bound; // becomes cumulative in place, with a leading 0
        for (std::size_t k = 0; k < runs; ++k) {
            const double end = k + 1 < runs ? start[k + 1] : maxLength;
            cumulative.push_back(cumulative.back() + value[k] * (end - start[k]));
            const double part = cb[k];
            cb[k] = b;
            b += part;
        }
        cb.push_back(b);
        if (labels) {
            const auto S = std::size_t(slotCount);
            cumLength.assign((runs + 1) * S, 0.0);
            for (std::size_t k = 0; k < runs; ++k) {
                const double end = k + 1 < runs ? start[k + 1] : maxLength;
                for (std::size_t j = 0; j < S; ++j) cumLength[(k + 1) * S + j] = cumLength[k * S + j];
                cumLength[(k + 1) * S + std::size_t(slotOfLabel[std::size_t(label[k])])] += end - start[k];
            }
            nextStart.assign((runs + 1) * S, kNotHit);
            for (std::size_t k = runs; k-- > 0;) {
                for (std::size_t j = 0; j < S; ++j) nextStart[k * S + j] = nextStart[(k + 1) * S + j];
                nextStart[k * S + std::size_t(slotOfLabel[std::size_t(label[k])])] = start[k];
            }
        }
        after.resize(runs);
        for (std::size_t k = 0; k < runs; ++k) after[k] = k + 1 < runs ? start[k + 1] : kNotHit;
        const auto buckets = std::size_t(std::ceil(maxLength / bucketWidth)) + 1;
        bucketRun.resize(buckets);
        std::size_t k = 0;
        for (std::size_t j = 0; j < buckets; ++j) {
            const double s = double(j) * bucketWidth;
            while (k + 1 < runs && start[k + 1] <= s) ++k;
            bucketRun[j] = std::uint32_t(k);
        }
    }

    /// The run holding arc length s in [0, maxLength]: O(1), a few steps past the
    /// bucket's first run. The first step is taken without a branch (whether s
    /// lies in the bucket's first run or a later one is data-dependent; the
    /// buckets are half a voxel, so a second step is rare); after[] ends in +inf.
    [[gnu::always_inline]] std::size_t runAt(double s) const noexcept
    {
        // Through a signed conversion: the unsigned one tests for 2^63 first.
        const auto j =
            std::min(bucketRun.size() - 1, std::size_t(std::int64_t(detail::walk::maxOf(0.0, s) * bucketsPerMm)));
        std::size_t k = bucketRun[j];
        k += std::size_t(after[k] <= s);
        while (after[k] <= s) ++k;
        return k;
    }
    double integralTo(double s, std::size_t k) const noexcept { return cumulative[k] + value[k] * (s - start[k]); }

    detail::FieldReaders src;
    bool labels;
    openvdb::math::Transform::ConstPtr xform;
    openvdb::Vec3d lo{1.0}, hi{-1.0};
    std::array<Vec3d, 3> worldToIndexRow;

    bool locked = false;
    Vec3d origin{0, 0, 0}, u{0, 0, 1};
    double originIndex[3] = {0, 0, 0}, rate[3] = {0, 0, 0}, reachIndex[3] = {0, 0, 0};

    std::vector<double> start, cumulative, value, bound;
    std::vector<double> after; ///< start of the next run; kNotHit (+inf) after the last
    std::vector<int> label;
    std::vector<std::uint32_t> bucketRun;
    double bucketWidth = 1.0;
    double bucketsPerMm = 1.0; ///< 1/bucketWidth: runAt runs at servo rate, a multiply instead of a divide
    std::size_t maxRuns = 0;
    std::array<int, kMaxLabels> slotOfLabel{};
    std::array<int, kMaxLabels> labelOfSlot{}; ///< the labels on the line, in slot order
    int slotCount = 0;
    std::vector<double> cumLength; // [(run) * slots + slot]: length in the slot's label before the run
    std::vector<double> nextStart; // [(run) * slots + slot]: start of the first run at or after it with that label
};

TrajectoryProfile::TrajectoryProfile(
    const MaterialField& field, double toleranceMm, double maxLengthMm, bool trackLabels)
    : mImpl(std::make_unique<Impl>(field, toleranceMm, maxLengthMm, trackLabels)), mTolerance(toleranceMm),
      mMaxLength(maxLengthMm)
{
    mImpl->clear();
}

TrajectoryProfile::~TrajectoryProfile() = default;

TrajectoryProfile::TrajectoryProfile(const TrajectoryProfile& o)
    : mImpl(std::make_unique<Impl>(*o.mImpl)), mTolerance(o.mTolerance), mMaxLength(o.mMaxLength),
      mRebuilds(o.mRebuilds)
{
    mImpl->reserveAll(mMaxLength);
}

std::unique_ptr<ShaftIntegrator> TrajectoryProfile::clone() const { return std::make_unique<TrajectoryProfile>(*this); }

std::string TrajectoryProfile::name() const
{
    std::ostringstream os;
    os << "profile tol=" << mTolerance << "mm";
    return os.str();
}

std::size_t TrajectoryProfile::runs() const { return mImpl->start.size(); }

bool TrajectoryProfile::lock(const Vec3d& origin, const Vec3d& direction) noexcept
{
    ++mRebuilds;
    return mImpl->build(origin, direction, mMaxLength, mTolerance);
}

namespace {

/// Where a shaft lies against the locked line: its ends' arc lengths along it
/// and whether both ends are within the tolerance. Squared distances (no square
/// roots): this runs at servo rate.
struct LinePlace {
    double se = 0, st = 0;
    bool covered = false;
};

[[gnu::always_inline]] inline LinePlace placeOnLine(
    const Vec3d& origin, const Vec3d& u, const Segment& s, double tolerance, double maxLength) noexcept
{
    LinePlace p;
    const Vec3d e = s.entry - origin, t = s.tip - origin;
    p.se = e.dot(u);
    p.st = t.dot(u);
    const double tol2 = tolerance * tolerance;
    const double de2 = e.squaredNorm() - p.se * p.se, dt2 = t.squaredNorm() - p.st * p.st;
    p.covered = de2 <= tol2 && dt2 <= tol2 && p.se >= -tolerance && p.st >= p.se && p.st <= maxLength;
    return p;
}

} // namespace

bool TrajectoryProfile::covers(const Segment& s) const noexcept
{
    const Impl& m = *mImpl;
    if (!m.locked || !s.entry.allFinite() || !s.tip.allFinite()) return false;
    return placeOnLine(m.origin, m.u, s, mTolerance, mMaxLength).covered;
}

void TrajectoryProfile::integrate(const Segment& s, ShaftIntegral& out) noexcept
{
    Impl& m = *mImpl;
    out.reset(m.labels); // the label arrays only when this profile fills them
    const double length = (s.tip - s.entry).norm();
    LinePlace place = placeOnLine(m.origin, m.u, s, mTolerance, mMaxLength);
    // A non-finite entry makes place.se non-finite, a non-finite tip the length.
    if (!std::isfinite(length) || !std::isfinite(place.se)) return;
    out.lengthMm = length;
    if (!(length > 0.0)) return;
    if (!m.locked || !place.covered || length > mMaxLength) [[unlikely]] {
        // The rare paths out of line, so that the servo's path keeps its registers.
        if (!integrateOffLine(s, length, out)) return;
        place = placeOnLine(m.origin, m.u, s, mTolerance, mMaxLength);
    }
    using detail::walk::maxOf, detail::walk::minOf; // minsd and maxsd, where std::clamp branches
    const double se = minOf(maxOf(place.se, 0.0), mMaxLength);
    const double st = minOf(maxOf(place.st, se), mMaxLength);
    const double projected = st - se;
    // The shaft is ℓ' long where the line piece is ℓ: scale by ℓ'/ℓ (1 on the line).
    const double scale = projected > 0.0 ? length / projected : 0.0;
    const std::size_t ke = m.runAt(se), kt = m.runAt(st);
    out.dampingIntegral = scale * (m.integralTo(st, kt) - m.integralTo(se, ke));
    if (m.labels) fillLabels(se, st, ke, kt, scale, out);
}

bool TrajectoryProfile::integrateOffLine(const Segment& s, double length, ShaftIntegral& out) noexcept
{
    Impl& m = *mImpl;
    if (length > mMaxLength) { // beyond the profile's reach: one exact traversal, no line kept
        const detail::IndexSegment direct = detail::toIndex(*m.xform, s, 0.5);
        out.labelsValid = m.labels;
        detail::chordPass(direct, m.lo, m.hi, m.src.betaCursorPtr(), m.src.labelCursorPtr(), out);
        return false;
    }
    return lock(s.entry, s.tip - s.entry);
}

void TrajectoryProfile::integratePolyline(std::span<const Vec3d> points, ShaftIntegral& out) noexcept
{
    Impl& m = *mImpl;
    out.reset(m.labels);
    out.labelsValid = m.labels;
    // The exact traversal's own index map: the same answer as ExactVoxel, bit for bit.
    detail::polylineChordPass(m.src.indexMap, points, m.lo, m.hi, m.src.betaCursorPtr(), m.src.labelCursorPtr(), out);
}

void TrajectoryProfile::fillLabels(
    double se, double st, std::size_t ke, std::size_t kt, double scale, ShaftIntegral& out) const noexcept
{
    const Impl& m = *mImpl;
    out.labelsValid = true;
    const auto S = std::size_t(m.slotCount);
    // Only the labels the line meets (the others keep reset()'s zero length and
    // no hit): a handful, where a loop over every label was 64 steps per tick.
    for (std::size_t j = 0; j < S; ++j) {
        const int l = m.labelOfSlot[j];
        const auto lengthTo = [&](double x, std::size_t k) {
            return m.cumLength[k * S + j] + (m.label[k] == l ? x - m.start[k] : 0.0);
        };
        out.labelLengthMm[std::size_t(l)] = scale * (lengthTo(st, kt) - lengthTo(se, ke));
        const double next = m.label[ke] == l ? se : m.nextStart[ke * S + j];
        if (next < st) out.firstHitMm[std::size_t(l)] = scale * (next - se);
    }
}

double TrajectoryProfile::errorBound(const Segment& s) const noexcept
{
    const Impl& m = *mImpl;
    if (!covers(s)) return kNotHit;
    const double se = std::clamp((s.entry - m.origin).dot(m.u), 0.0, mMaxLength);
    const double st = std::clamp((s.tip - m.origin).dot(m.u), se, mMaxLength);
    const double length = (s.tip - s.entry).norm();
    const double scale = st > se ? length / (st - se) : 1.0;
    // Whole runs at both ends: conservative.
    return scale * (m.bound[m.runAt(st) + 1] - m.bound[m.runAt(se)]);
}

} // namespace voxhap::haptic
