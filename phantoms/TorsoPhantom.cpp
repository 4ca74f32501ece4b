// SPDX-License-Identifier: Apache-2.0
/// @file TorsoPhantom.cpp
/// @brief Spine-biopsy torso: the organs of the [K01] simulator (physics.md §1.1)
/// around a lumbar vertebra with a lytic lesion.

#include "phantoms/Phantoms.h"

#include "core/Errors.h"

#include <cmath>
#include <sstream>

namespace voxhap::volume {

namespace {

// All dimensions in mm [chosen]: an adult lower torso in LPS, posterior skin at
// y = 0 on the midline, the body centred 100 mm anterior of it.
constexpr double kHalfWidth = 150.0; ///< body ellipse semi-axis along x (left-right)
constexpr double kHalfDepth = 100.0; ///< body ellipse semi-axis along y (anterior-posterior)
constexpr double kCentreY = -100.0;  ///< body centre
constexpr double kSkin = 2.0;        ///< skin shell
constexpr double kFat = 15.0;        ///< subcutaneous fat
constexpr double kHalfLength = 60.0; ///< half extent along z (cranio-caudal)

constexpr double kBodyY = -77.0; ///< vertebral body axis (x = 0)
constexpr double kBodyRadius = 18.0;
constexpr double kVertebraHeight = 28.0; ///< vertebral body height; the lesion's vertebra is centred at z = 0
constexpr double kTorsoDiscHeight = 10.0;
constexpr double kCanalY = -50.0; ///< spinal canal axis
constexpr double kCanalRadius = 9.0;
constexpr double kCordRadius = 4.0;
constexpr double kArchOuterRadius = 14.0; ///< laminae and pedicles: posterior half-annulus around the canal
constexpr double kSpinousHalfWidth = 4.0;
constexpr double kSpinousTipY = -22.0; ///< spinous process tip, 22 mm under the skin

const Vec3d kLesionCentre(5.0, -78.0, 0.0);
const Vec3d kAortaAxis(15.0, -110.0, 0.0); ///< left of midline (+x), anterior of the spine
constexpr double kAortaRadius = 11.0;
const Vec3d kKidneyCentre(75.0, -70.0, -20.0); ///< mirrored in x for the right kidney
const Vec3d kKidneySemiAxes(25.0, 20.0, 45.0);
const Vec3d kLungCentre(70.0, -80.0, 90.0); ///< lung bases reach down to z = 30
const Vec3d kLungSemiAxes(55.0, 55.0, 60.0);

bool inEllipsoid(const Vec3d& p, const Vec3d& c, const Vec3d& semi)
{
    return ((p - c).array() / semi.array()).square().sum() < 1.0;
}

double ellipse(double x, double y, double a, double b) { return (x / a) * (x / a) + (y / b) * (y / b); }

} // namespace

PhantomModel torsoModel(const TorsoParams& p, const TissueTable& table)
{
    if (!std::isfinite(p.lesionRadiusMm) || p.lesionRadiusMm <= 0.0 || p.lesionRadiusMm > 12.0) {
        throw ValueError("torso phantom: lesion radius must be in (0, 12] mm to stay inside the vertebral body");
    }
    const auto id = [&](const char* name) { return table.at(name).id; };
    const int skin = id("skin"), fat = id("fat"), muscle = id("muscle"), lung = id("lung"), kidney = id("kidney");
    const int aorta = id("aorta"), lesion = id("lesion"), cortical = id("cortical_bone");
    const int cancellous = id("cancellous_bone"), disc = id("intervertebral_disc"), csf = id("csf");
    const int cord = id("spinal_cord"), inter = id("interspinous_ligament"), flavum = id("ligamentum_flavum");
    const double shell = table.at("cortical_bone").thickness ? table.at("cortical_bone").thickness->value : 1.5;
    const double lesionR2 = p.lesionRadiusMm * p.lesionRadiusMm;

    PhantomModel m;
    m.kind = "torso";
    std::ostringstream desc;
    desc << "spine-biopsy torso, lesion r " << p.lesionRadiusMm << " mm";
    m.description = desc.str();
    m.classify = [=](const Vec3d& w) -> int {
        const double x = w.x(), y = w.y() - kCentreY, z = w.z();
        if (std::abs(z) > kHalfLength) return 0;
        if (ellipse(x, y, kHalfWidth, kHalfDepth) >= 1.0) return 0;
        if (ellipse(x, y, kHalfWidth - kSkin, kHalfDepth - kSkin) >= 1.0) return skin;
        if (ellipse(x, y, kHalfWidth - kSkin - kFat, kHalfDepth - kSkin - kFat) >= 1.0) return fat;
        const Vec3d mirrored(std::abs(x), w.y(), z);
        if (inEllipsoid(mirrored, kLungCentre, kLungSemiAxes)) return lung;
        if (inEllipsoid(mirrored, kKidneyCentre, kKidneySemiAxes)) return kidney;
        if (std::hypot(x - kAortaAxis.x(), w.y() - kAortaAxis.y()) < kAortaRadius) return aorta;
        if ((w - kLesionCentre).squaredNorm() < lesionR2) return lesion;

        // Vertebral column: bodies and discs repeat along z, the lesion's body centred at z = 0.
        const double period = kVertebraHeight + kTorsoDiscHeight;
        const double phase = std::fmod(std::fmod(z + 0.5 * kVertebraHeight, period) + period, period);
        const bool bodyLevel = phase < kVertebraHeight;
        const double rBody = std::hypot(x, w.y() - kBodyY);
        if (rBody < kBodyRadius) {
            if (!bodyLevel) return disc;
            const double s = std::min({kBodyRadius - rBody, phase, kVertebraHeight - phase});
            return s < shell ? cortical : cancellous;
        }
        const double rCanal = std::hypot(x, w.y() - kCanalY);
        if (rCanal < kCordRadius) return cord;
        if (rCanal < kCanalRadius) return csf;
        // Posterior arch (laminae, pedicles) and spinous process: bone at the body's
        // level, ligaments (flavum, interspinous) at the disc's.
        if (rCanal < kArchOuterRadius && w.y() >= kCanalY) return bodyLevel ? cortical : flavum;
        if (std::abs(x) <= kSpinousHalfWidth && w.y() > kCanalY && w.y() <= kSpinousTipY) {
            if (!bodyLevel) return inter;
            const double s =
                std::min({kSpinousHalfWidth - std::abs(x), kSpinousTipY - w.y(), phase, kVertebraHeight - phase});
            return s < shell ? cortical : cancellous;
        }
        return muscle;
    };
    m.bounds = {Vec3d(-kHalfWidth - 2.0, kCentreY - kHalfDepth - 2.0, -kHalfLength),
        Vec3d(kHalfWidth + 2.0, kCentreY + kHalfDepth + 2.0, kHalfLength)};

    // Reference path: posterolateral, 25 degrees from the sagittal plane, skin to lesion
    // centre, passing lateral of the spinal canal (a transpedicular-like approach).
    const double angle = degToRad(25.0);
    const Vec3d outward(std::sin(angle), std::cos(angle), 0.0);
    double lo = 0.0, hi = 400.0; // bisection for the skin crossing
    for (int it = 0; it < 200; ++it) {
        const double mid = 0.5 * (lo + hi);
        const Vec3d q = kLesionCentre + mid * outward;
        (ellipse(q.x(), q.y() - kCentreY, kHalfWidth, kHalfDepth) < 1.0 ? lo : hi) = mid;
    }
    m.pathEntry = kLesionCentre + lo * outward;
    m.pathTarget = kLesionCentre;
    m.landmarks = {{"entry", m.pathEntry}, {"lesion", kLesionCentre}, {"aorta", kAortaAxis},
        {"kidney_left", kKidneyCentre},
        {"kidney_right", Vec3d(-kKidneyCentre.x(), kKidneyCentre.y(), kKidneyCentre.z())},
        {"spinal_canal", Vec3d(0.0, kCanalY, 0.0)}};
    return m;
}

} // namespace voxhap::volume
