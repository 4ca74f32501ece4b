// SPDX-License-Identifier: Apache-2.0
/// @file Palpation.cpp
/// @brief The skin map (set-up) and the god-object palpation contact (servo path):
/// physics.md §6.1, §6.2 (proxy, virtual coupling), §6.4 (passivity), §4 (bone
/// texture), §5.2 (HU thresholds). See Palpation.h.

#include "haptic/force/Palpation.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <Eigen/Geometry> // for cross and unitOrthogonal
#include <openvdb/tools/Interpolation.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace voxhap::haptic {

namespace {

using Vec2 = Eigen::Vector2d;
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Bisection steps that place a boundary found between two samples: 40 halvings of
/// a quarter voxel leave it within 1e-12 mm, far below any tolerance of its users.
constexpr int kBisections = 40;
/// Descent iterations of the proxy per tick, and step halvings per iteration: the
/// proxy needs only to lower G each tick (Palpation.h), so a bounded few suffice;
/// 12 Newton-like steps converge on the smooth pieces of the map.
constexpr int kDescentSteps = 12;
constexpr int kHalvings = 20;
/// Friction cone search along the slip segment.
constexpr int kConeBisections = 24;

/// A column's predicate along the ray start + t·u: is the point tissue, is it bone?
struct ColumnProbe {
    virtual ~ColumnProbe() = default;
    virtual bool tissue(const Vec3d& p) = 0;
    virtual bool bone(const Vec3d& p) = 0;
};

struct LabelProbe final : ColumnProbe {
    LabelProbe(const volume::LabelGrid& g, const std::vector<char>& rigidById)
        : acc(g.getConstAccessor()), xf(g.transform()), rigid(rigidById)
    {
    }
    int label(const Vec3d& p) { return acc.getValue(xf.worldToIndexCellCentered(volume::toVdb(p))); }
    bool tissue(const Vec3d& p) override { return label(p) != 0; }
    bool bone(const Vec3d& p) override
    {
        const int l = label(p);
        return l > 0 && std::size_t(l) < rigid.size() && rigid[std::size_t(l)];
    }
    volume::LabelGrid::ConstAccessor acc;
    const openvdb::math::Transform& xf;
    const std::vector<char>& rigid;
};

struct HuProbe final : ColumnProbe {
    HuProbe(const volume::FloatGrid& g, double skinThreshold, double boneThreshold)
        : acc(g.getConstAccessor()), sampler(acc, g.transform()), skinHu(skinThreshold), boneHu(boneThreshold)
    {
    }
    double hu(const Vec3d& p) { return double(sampler.wsSample(volume::toVdb(p))); }
    bool tissue(const Vec3d& p) override { return hu(p) > skinHu; }
    bool bone(const Vec3d& p) override { return hu(p) >= boneHu; }
    volume::FloatGrid::ConstAccessor acc;
    openvdb::tools::GridSampler<volume::FloatGrid::ConstAccessor, openvdb::tools::BoxSampler> sampler;
    double skinHu, boneHu;
};

/// First t in [t0, t1] where @p pred turns true along start + t·u, stepping by @p step
/// and bisecting the last step; +∞ when it never does.
template <typename Pred>
double firstTrue(Pred&& pred, const Vec3d& start, const Vec3d& u, double t0, double t1, double step)
{
    if (pred(start + t0 * u)) return t0;
    double lo = t0;
    for (double t = t0 + step;; t += step) {
        const double hi = std::min(t, t1);
        if (pred(start + hi * u)) {
            double a = lo, b = hi;
            for (int k = 0; k < kBisections; ++k) {
                const double m = 0.5 * (a + b);
                (pred(start + m * u) ? b : a) = m;
            }
            return b;
        }
        if (hi >= t1) return kInf;
        lo = hi;
    }
}

} // namespace

SkinMap::SkinMap(const volume::Volume& vol, const volume::TissueTable& table, const Vec3d& origin, const Vec3d& inward,
    const PalpationParams& p, double deviceStiffness)
    : mOrigin(origin)
{
    const double n = inward.norm();
    if (!origin.allFinite() || !inward.allFinite() || !(n > 0.0))
        throw ValueError("palpation: the path's origin and direction must be finite and the direction non-zero");
    mU = inward / n;
    mE1 = mU.unitOrthogonal();
    mE2 = mU.cross(mE1);

    const volume::Geometry g = vol.geometry();
    const double voxel = g.spacing.minCoeff();
    mStep = p.gridMm > 0.0 ? p.gridMm : std::max(0.25, voxel);
    mN = 2 * int(std::ceil(p.radiusMm / mStep)) + 1;
    mHalf = 0.5 * double(mN - 1) * mStep;
    if (double(mN) * double(mN) > 4e6)
        throw ValueError("palpation: radius_mm / grid_mm gives more than 4e6 map nodes: use a coarser grid_mm");

    mEA = p.modulusKPa * p.contactAreaMm2 * 1e-3; // kPa·mm² = 1e3 N/m² · 1e-6 m² = 1e-3 N
    mKMax = p.maxStiffnessNPerMm > 0.0 ? p.maxStiffnessNPerMm : deviceStiffness;
    mKMin = std::min(p.minStiffnessNPerMm, mKMax);
    mMuSoft = p.frictionSoft;
    mMuBone = p.frictionBone;

    const bool labels = vol.has(volume::Channel::Label);
    const bool hu = vol.has(volume::Channel::Hu);
    if (p.source == SkinSource::Labels && !labels)
        throw ValueError("palpation: source \"labels\": the volume has no tissue labels");
    if (p.source == SkinSource::Hu && !hu) throw ValueError("palpation: source \"hu\": the volume has no HU grid");
    if (p.source == SkinSource::Auto && !labels && !hu)
        throw ValueError("palpation: the volume has neither tissue labels nor HU to find the skin in");
    mFromLabels = p.source == SkinSource::Labels || (p.source == SkinSource::Auto && labels);

    std::vector<char> rigid(std::size_t(table.maxId()) + 1, 0);
    for (const volume::Tissue& t : table.tissues()) rigid[std::size_t(t.id)] = t.rigid;
    const auto labelGrid = volume::labelGrid(vol);
    const auto huGrid = volume::huGrid(vol);

    mNodes.assign(std::size_t(mN) * std::size_t(mN), Node{});
    const double step = 0.25 * voxel;
    const double length = p.aboveMm + p.reachMm; // the skin may lie above or below the entry
    tbb::parallel_for(0, mN, [&](int j) {
        std::unique_ptr<ColumnProbe> probe;
        if (mFromLabels)
            probe = std::make_unique<LabelProbe>(*labelGrid, rigid);
        else
            probe = std::make_unique<HuProbe>(*huGrid, p.skinHu, p.boneHu);
        for (int i = 0; i < mN; ++i) {
            const double a = -mHalf + i * mStep, b = -mHalf + j * mStep;
            const Vec3d start = mOrigin + a * mE1 + b * mE2 - p.aboveMm * mU;
            const double skin =
                firstTrue([&](const Vec3d& x) { return probe->tissue(x); }, start, mU, 0.0, length, step);
            Node& nd = mNodes[std::size_t(j) * std::size_t(mN) + std::size_t(i)];
            if (!std::isfinite(skin)) continue;
            nd.skin = skin - p.aboveMm;
            const double bone =
                firstTrue([&](const Vec3d& x) { return probe->bone(x); }, start, mU, skin, skin + p.reachMm, step);
            nd.thickness = std::isfinite(bone) ? bone - skin : kInf;
            nd.k = stiffnessFor(nd.thickness);
            nd.mu = frictionFor(nd.k);
        }
    });
    for (const Node& nd : mNodes) {
        mSkinNodes += std::isfinite(nd.skin);
        mBoneNodes += std::isfinite(nd.skin) && std::isfinite(nd.thickness);
    }
    if (mSkinNodes == 0) {
        throw ValueError(std::string("palpation: no skin within ") + std::to_string(p.radiusMm) +
            " mm of the entry across the path (from " + (mFromLabels ? "labels" : "HU") + ")");
    }
}

double SkinMap::stiffnessFor(double T) const noexcept
{
    if (!(T > 0.0)) return mKMax; // bone at the skin
    return std::clamp(mEA / T, mKMin, mKMax);
}

double SkinMap::frictionFor(double k) const noexcept
{
    if (!(mKMax > mKMin)) return mMuSoft;
    return mMuSoft + (mMuBone - mMuSoft) * std::clamp((k - mKMin) / (mKMax - mKMin), 0.0, 1.0);
}

Vec3d SkinMap::toMap(const Vec3d& w) const noexcept
{
    const Vec3d r = w - mOrigin;
    return {r.dot(mE1), r.dot(mE2), r.dot(mU)};
}

Vec3d SkinMap::toWorld(const Vec3d& m) const noexcept { return mOrigin + m.x() * mE1 + m.y() * mE2 + m.z() * mU; }

SkinSample SkinMap::sample(double a, double b) const noexcept
{
    SkinSample s;
    if (!std::isfinite(a) || !std::isfinite(b)) return s;
    // Outside the map the border extends: clamp, and the clamped direction has no slope.
    const double x = std::clamp((a + mHalf) / mStep, 0.0, double(mN - 1));
    const double y = std::clamp((b + mHalf) / mStep, 0.0, double(mN - 1));
    const int i = std::min(int(x), mN - 2), j = std::min(int(y), mN - 2);
    const double fx = x - i, fy = y - j;
    const Node &n00 = node(i, j), &n10 = node(i + 1, j), &n01 = node(i, j + 1), &n11 = node(i + 1, j + 1);
    if (std::isnan(n00.skin) || std::isnan(n10.skin) || std::isnan(n01.skin) || std::isnan(n11.skin)) return s;
    const bool inA = (a + mHalf) / mStep > 0.0 && (a + mHalf) / mStep < double(mN - 1);
    const bool inB = (b + mHalf) / mStep > 0.0 && (b + mHalf) / mStep < double(mN - 1);
    const auto lerp2 = [&](double v00, double v10, double v01, double v11, double& da, double& db) {
        da = inA ? ((1 - fy) * (v10 - v00) + fy * (v11 - v01)) / mStep : 0.0;
        db = inB ? ((1 - fx) * (v01 - v00) + fx * (v11 - v10)) / mStep : 0.0;
        return (1 - fx) * (1 - fy) * v00 + fx * (1 - fy) * v10 + (1 - fx) * fy * v01 + fx * fy * v11;
    };
    double ia = 0, ib = 0;
    s.surface = true;
    s.skinMm = lerp2(n00.skin, n10.skin, n01.skin, n11.skin, s.gradA, s.gradB);
    s.stiffnessNPerMm = lerp2(n00.k, n10.k, n01.k, n11.k, s.gradKA, s.gradKB);
    s.friction = lerp2(n00.mu, n10.mu, n01.mu, n11.mu, ia, ib);
    // T for the record: the node nearest (infinite thicknesses do not interpolate).
    s.thicknessMm = node(fx < 0.5 ? i : i + 1, fy < 0.5 ? j : j + 1).thickness;
    return s;
}

bool PalpationContact::inside(const Vec3d& tip) const noexcept
{
    const Vec3d m = mMap->toMap(tip);
    const SkinSample s = mMap->sample(m.x(), m.y());
    return s.surface && m.z() > s.skinMm;
}

void PalpationContact::reset() noexcept
{
    mHave = mOnSurface = false;
    mOut = PalpationOutput{};
}

double PalpationContact::energy(const Vec3d& x, const Vec3d& p, SkinSample* at) const noexcept
{
    const SkinSample s = mMap->sample(x.x(), x.y());
    if (at) *at = s;
    const double k = s.surface ? s.stiffnessNPerMm : mMap->minStiffness();
    return 0.5 * k * (x - p).squaredNorm();
}

const PalpationOutput& PalpationContact::update(const Vec3d& tip) noexcept
{
    const SkinMap& map = *mMap;
    const Vec3d p = map.toMap(tip);
    const SkinSample here = map.sample(p.x(), p.y());
    if (!p.allFinite() || !here.surface || p.z() <= here.skinMm) { // free: the proxy is the tip
        mOut = PalpationOutput{};
        mOut.proxy = tip;
        mProxy = p;
        mHave = p.allFinite();
        mOnSurface = false;
        return mOut;
    }
    // The points outside the skin the proxy may take, each never raising G(X, p):
    // the last proxy (outside by induction), the skin straight above the tip, and a
    // descent from the better of the two along the skin.
    const Vec3d vertical(p.x(), p.y(), here.skinMm);
    const double gVertical = energy(vertical, p);
    const double gLast = mHave ? energy(mProxy, p) : kInf;
    const bool lastOnSurface = mHave && mOnSurface;
    Vec3d best = gVertical <= gLast ? vertical : mProxy;
    double gBest = std::min(gVertical, gLast);
    bool bestOnSurface = gVertical <= gLast || lastOnSurface;

    // Frictionless minimum of g(q) = ½·k(q)·(|q − q_p|² + (s(q) − d_p)²) over the skin,
    // Newton-like steps with step halving (G only falls).
    Vec2 q(best.x(), best.y());
    SkinSample sq = map.sample(q.x(), q.y());
    double gq = sq.surface ? 0.5 * sq.stiffnessNPerMm *
            ((q - Vec2(p.x(), p.y())).squaredNorm() + (sq.skinMm - p.z()) * (sq.skinMm - p.z()))
                           : kInf;
    for (int it = 0; it < kDescentSteps && std::isfinite(gq); ++it) {
        const Vec2 r = q - Vec2(p.x(), p.y());
        const double h = sq.skinMm - p.z();
        const double d2 = r.squaredNorm() + h * h;
        const Vec2 grad =
            0.5 * d2 * Vec2(sq.gradKA, sq.gradKB) + sq.stiffnessNPerMm * (r + h * Vec2(sq.gradA, sq.gradB));
        const double curv = std::max(1e-9, sq.stiffnessNPerMm * (1.0 + sq.gradA * sq.gradA + sq.gradB * sq.gradB));
        Vec2 stepv = -grad / curv;
        bool moved = false;
        for (int k = 0; k < kHalvings; ++k, stepv *= 0.5) {
            const Vec2 qn = q + stepv;
            const SkinSample sn = map.sample(qn.x(), qn.y());
            if (!sn.surface) continue;
            const double hn = sn.skinMm - p.z();
            const double gn = 0.5 * sn.stiffnessNPerMm * ((qn - Vec2(p.x(), p.y())).squaredNorm() + hn * hn);
            if (gn < gq) {
                q = qn, sq = sn, gq = gn, moved = true;
                break;
            }
        }
        if (!moved || stepv.norm() < 1e-12) break;
    }
    const Vec3d star(q.x(), q.y(), sq.skinMm);
    if (gq < gBest) best = star, gBest = gq, bestOnSurface = true;

    // Coulomb friction at the proxy (the texture): a proxy resting on the skin stays
    // while the tangential force is within μ times the normal force; when it slips it
    // goes only as far toward the frictionless minimum as the cone needs.
    Vec3d x = best;
    bool onSurface = bestOnSurface;
    if (lastOnSurface) {
        SkinSample s0;
        const double g0 = energy(mProxy, p, &s0);
        const auto withinCone = [&](const Vec3d& at, const SkinSample& s) {
            const Vec3d f = s.stiffnessNPerMm * (at - p);
            const Vec3d out = Vec3d(s.gradA, s.gradB, -1.0).normalized(); // outward normal
            const double fn = f.dot(out);
            return fn > 0.0 && (f - fn * out).norm() <= s.friction * fn;
        };
        if (s0.surface && withinCone(mProxy, s0)) {
            x = mProxy; // stick
        } else if (s0.surface) {
            const Vec2 q0(mProxy.x(), mProxy.y());
            double lo = 0.0, hi = 1.0;
            for (int k = 0; k < kConeBisections; ++k) {
                const double m = 0.5 * (lo + hi);
                const Vec2 qm = q0 + m * (q - q0);
                const SkinSample sm = map.sample(qm.x(), qm.y());
                const bool ok = sm.surface && withinCone(Vec3d(qm.x(), qm.y(), sm.skinMm), sm);
                (ok ? hi : lo) = m;
            }
            const Vec2 qs = q0 + hi * (q - q0);
            const SkinSample ss = map.sample(qs.x(), qs.y());
            const Vec3d slip(qs.x(), qs.y(), ss.skinMm);
            if (ss.surface && energy(slip, p) <= g0) x = slip, onSurface = true;
        }
    }
    SkinSample sx;
    const double g = energy(x, p, &sx);
    mProxy = x;
    mHave = true;
    mOnSurface = onSurface;
    const double k = sx.surface ? sx.stiffnessNPerMm : map.minStiffness();
    mOut.contact = true;
    mOut.proxy = map.toWorld(x);
    mOut.force = k * (mOut.proxy - tip);
    mOut.indentationMm = (x - p).norm();
    mOut.stiffnessNPerMm = k;
    mOut.friction = sx.surface ? sx.friction : 0.0;
    mOut.thicknessMm = sx.thicknessMm;
    mOut.energyNmm = g;
    return mOut;
}

} // namespace voxhap::haptic
