// SPDX-License-Identifier: Apache-2.0
/// @file MetricStage.cpp
/// @brief ITK v4 registration pieces: Mattes MI, regular-step gradient descent,
/// Euler 3D and affine transforms, body masks and a fixed sample set.

#include "registration/detail/MetricStage.h"

#include "core/Errors.h"

#include <itkAffineTransform.h>
#include <itkCommand.h>
#include <itkEuler3DTransform.h>
#include <itkImage.h>
#include <itkMattesMutualInformationImageToImageMetricv4.h>
#include <itkRegularStepGradientDescentOptimizerv4.h>
#include <itkSpatialObject.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <tuple>

#include <tbb/parallel_invoke.h>

namespace voxhap::registration::detail {

// Not an anonymous namespace: MetricPair::Impl, declared in the header's
// namespace, holds these types, and a member of an anonymously namespaced type
// would give Impl a linkage of its own (GCC's -Wsubobject-linkage).
namespace stage {

using ImageF = itk::Image<float, 3>;
using MattesMetric = itk::MattesMutualInformationImageToImageMetricv4<ImageF, ImageF>;

/// ITK's Mattes mutual information, split over work units with the same
/// answer on every run. ITK's own threader sums each unit's derivative
/// contributions into one shared buffer under a try-lock, whenever a unit's
/// small buffer fills and at its end, in whatever order the units get there:
/// the sums, and from them the optimiser's path, changed from run to run (the
/// porcine pair's answer moved by a millimetre). Here each unit reduces into a
/// buffer of its own, in its samples' order, and the units' buffers are added
/// to ITK's in unit order once all have finished. The joint histograms ITK
/// already adds in unit order. The partition of the samples into units is
/// fixed by their count, so a given number of units gives the same bits on any
/// machine. One unit reproduces ITK's serial sums exactly.
class OrderedMattes : public MattesMetric {
public:
    ITK_DISALLOW_COPY_AND_MOVE(OrderedMattes);
    using Self = OrderedMattes;
    using Superclass = MattesMetric;
    using Pointer = itk::SmartPointer<Self>;
    using ConstPointer = itk::SmartPointer<const Self>;
    itkNewMacro(Self)
    itkTypeMacro(OrderedMattes, MattesMutualInformationImageToImageMetricv4);
    using SparseThreader = Superclass::MattesMutualInformationSparseGetValueAndDerivativeThreaderType;

    /// @brief Use @p units work units for the sampled points (split in index
    /// order). The dense threader, which a sampled metric does not run, keeps one.
    void setWorkUnits(itk::ThreadIdType units)
    {
        this->SetMaximumNumberOfWorkUnits(units);
        this->m_SparseGetValueAndDerivativeThreader->SetNumberOfWorkUnits(units);
    }

    /// @brief Point each unit's derivative buffer at a sum of its own. Called
    /// by the threader after ITK has set the buffers up for this evaluation,
    /// before any unit starts.
    void giveEachUnitItsOwnSum(itk::ThreadIdType units)
    {
        if (!this->GetComputeDerivative() || this->HasLocalSupport()) return;
        const auto region = this->m_JointPDFDerivatives->GetBufferedRegion();
        if (mUnitSums.size() != units) {
            mUnitSums.assign(units, nullptr);
            mUnitLocks = std::vector<std::mutex>(units);
        }
        for (itk::ThreadIdType u = 0; u < units; ++u) {
            if (mUnitSums[u].IsNull() || mUnitSums[u]->GetBufferedRegion() != region) {
                mUnitSums[u] = JointPDFDerivativesType::New();
                mUnitSums[u]->SetRegions(region);
                mUnitSums[u]->Allocate();
            }
            mUnitSums[u]->FillBuffer(0.0);
            // ITK's own buffer length for this many units (its threader's
            // BeforeThreadedExecution), with this unit's lock and sum.
            const std::size_t bins = this->m_NumberOfHistogramBins;
            this->m_ThreaderDerivativeManager[u].Initialize(std::max<std::size_t>(500, bins * bins / units),
                this->GetNumberOfLocalParameters(), &mUnitLocks[u], mUnitSums[u]);
        }
    }

protected:
    OrderedMattes();
    ~OrderedMattes() override = default;

    /// The units' sums into ITK's, in unit order, before ITK's own reduction
    /// of the histograms and its scaling of the derivative sums.
    void GetValueCommonAfterThreadedExecution() override
    {
        if (this->GetComputeDerivative() && !this->HasLocalSupport()) {
            const itk::SizeValueType n = this->m_JointPDFDerivatives->GetBufferedRegion().GetNumberOfPixels();
            JointPDFDerivativesValueType* total = this->m_JointPDFDerivatives->GetBufferPointer();
            const itk::ThreadIdType units = this->GetNumberOfWorkUnitsUsed();
            for (itk::ThreadIdType u = 0; u < units && u < mUnitSums.size(); ++u) {
                const JointPDFDerivativesValueType* part = mUnitSums[u]->GetBufferPointer();
                for (itk::SizeValueType i = 0; i < n; ++i) total[i] += part[i];
            }
        }
        Superclass::GetValueCommonAfterThreadedExecution();
    }

private:
    std::vector<typename JointPDFDerivativesType::Pointer> mUnitSums;
    std::vector<std::mutex> mUnitLocks; ///< one per unit: a unit's reductions never wait on another's
};

/// ITK's threader for sampled points, which hands each unit its own sum
/// before the units start (OrderedMattes::giveEachUnitItsOwnSum).
class OrderedMattesThreader : public OrderedMattes::SparseThreader {
public:
    ITK_DISALLOW_COPY_AND_MOVE(OrderedMattesThreader);
    using Self = OrderedMattesThreader;
    using Superclass = OrderedMattes::SparseThreader;
    using Pointer = itk::SmartPointer<Self>;
    itkNewMacro(Self)

protected:
    OrderedMattesThreader() = default;
    ~OrderedMattesThreader() override = default;
    void BeforeThreadedExecution() override
    {
        Superclass::BeforeThreadedExecution();
        static_cast<OrderedMattes*>(this->m_Associate)->giveEachUnitItsOwnSum(this->GetNumberOfWorkUnitsUsed());
    }
};

/// The metric samples a point set, so its sparse threader is the one that
/// runs; the dense one stays ITK's, on one unit.
OrderedMattes::OrderedMattes()
{
    this->m_SparseGetValueAndDerivativeThreader = OrderedMattesThreader::New();
    this->m_SparseGetValueAndDerivativeThreader->SetNumberOfWorkUnits(1);
    this->m_DenseGetValueAndDerivativeThreader->SetNumberOfWorkUnits(1);
}

using Metric = OrderedMattes;
using PointSet = Metric::FixedSampledPointSetType;
using Optimizer = itk::RegularStepGradientDescentOptimizerv4<double>;
using Rigid = itk::Euler3DTransform<double>;
using Affine = itk::AffineTransform<double, 3>;

/// An image on @p li's lattice holding @p region of it (default: the whole).
template <typename ImageT>
typename ImageT::Pointer emptyImage(const LevelImage& li, std::optional<typename ImageT::RegionType> region = {})
{
    auto img = ImageT::New();
    typename ImageT::SizeType size;
    typename ImageT::SpacingType spacing;
    typename ImageT::PointType origin;
    typename ImageT::DirectionType direction;
    for (unsigned a = 0; a < 3; ++a) {
        size[a] = itk::SizeValueType(li.dims[int(a)]);
        spacing[a] = li.geometry.spacing[int(a)];
        origin[a] = li.geometry.origin[int(a)];
        for (unsigned b = 0; b < 3; ++b) direction(a, b) = li.geometry.direction(int(a), int(b));
    }
    img->SetRegions(region.value_or(typename ImageT::RegionType(size)));
    img->SetSpacing(spacing);
    img->SetOrigin(origin);
    img->SetDirection(direction);
    img->Allocate();
    return img;
}

ImageF::Pointer toItk(const LevelImage& li)
{
    auto img = emptyImage<ImageF>(li);
    std::copy(li.values.begin(), li.values.end(), img->GetBufferPointer());
    return img;
}

/// The voxels a metric can read of a moving image whose samples count only
/// inside @p mask: the mask's box grown by @p margin voxels, on the image's own
/// index lattice (the region starts where the box does, so index and world
/// agree with the whole image). A point inside the mask lies within half a
/// voxel of a mask voxel; its linear interpolation reads the voxels within one
/// more, and the metric's central differences, one voxel to either side, one
/// more again: a margin of 3 holds every voxel the whole image would give. What
/// is left out lies outside the mask, where ITK's Mattes metric reads nothing,
/// not even for the moving image's value range, which it takes over the mask's
/// voxels of the buffer: a scan of the whole image at every initialisation,
/// a tenth of a torso phantom's registration, before the crop.
ImageF::Pointer toItkCropped(const LevelImage& li, const std::vector<std::uint8_t>& mask, int margin)
{
    Vec3i lo = li.dims, hi(-1, -1, -1);
    for (int k = 0; k < li.dims.z(); ++k) {
        for (int j = 0; j < li.dims.y(); ++j) {
            const std::int64_t row = li.index(0, j, k);
            for (int i = 0; i < li.dims.x(); ++i) {
                if (!mask[std::size_t(row + i)]) continue;
                lo = lo.cwiseMin(Vec3i(i, j, k));
                hi = hi.cwiseMax(Vec3i(i, j, k));
            }
        }
    }
    if ((hi.array() < 0).any()) return toItk(li); // no mask: the whole image
    lo = (lo.array() - margin).max(0);
    hi = (hi.array() + margin).min(li.dims.array() - 1);
    ImageF::RegionType region;
    for (unsigned a = 0; a < 3; ++a) {
        region.SetIndex(a, itk::IndexValueType(lo[int(a)]));
        region.SetSize(a, itk::SizeValueType(hi[int(a)] - lo[int(a)] + 1));
    }
    auto img = emptyImage<ImageF>(li, region);
    float* out = img->GetBufferPointer();
    for (int k = lo.z(); k <= hi.z(); ++k) {
        for (int j = lo.y(); j <= hi.y(); ++j) {
            const auto from = li.values.begin() + std::ptrdiff_t(li.index(lo.x(), j, k));
            out = std::copy(from, from + (hi.x() - lo.x() + 1), out);
        }
    }
    return img;
}

/// A body mask as the metric asks it, "is this world point inside?", answered
/// as ImageMaskSpatialObject answers it (the nearest voxel, rounding halves up)
/// but from a precomputed world-to-index map: ITK's own object went through its
/// object-to-world transforms and image at every sample and took a seventh of
/// the registration's time.
class LevelMask : public itk::SpatialObject<3> {
public:
    ITK_DISALLOW_COPY_AND_MOVE(LevelMask);
    using Self = LevelMask;
    using Superclass = itk::SpatialObject<3>;
    using Pointer = itk::SmartPointer<Self>;
    using ConstPointer = itk::SmartPointer<const Self>;
    itkNewMacro(Self)
    itkTypeMacro(LevelMask, SpatialObject);

    void set(const LevelImage& li, const std::vector<std::uint8_t>& mask)
    {
        mMask = mask;
        mDims = li.dims;
        mOrigin = li.geometry.origin;
        mWorldToIndex = (li.geometry.direction * li.geometry.spacing.asDiagonal()).inverse();
    }
    bool IsInsideInObjectSpace(const PointType& p) const override
    {
        const Vec3d c = mWorldToIndex * (Vec3d(p[0], p[1], p[2]) - mOrigin);
        const Vec3i i((c.array() + 0.5).floor().cast<int>());
        if ((i.array() < 0).any() || (i.array() >= mDims.array()).any()) return false;
        return mMask[std::size_t((std::int64_t(i.z()) * mDims.y() + i.y()) * mDims.x() + i.x())] != 0;
    }
    bool IsInsideInWorldSpace(const PointType& p, unsigned int, const std::string&) const override
    {
        return IsInsideInObjectSpace(p); // object space is world space here
    }

protected:
    LevelMask() = default;
    ~LevelMask() override = default;

private:
    std::vector<std::uint8_t> mMask;
    Vec3i mDims = Vec3i::Zero();
    Vec3d mOrigin = Vec3d::Zero();
    Mat3d mWorldToIndex = Mat3d::Identity();
};
using MaskObject = LevelMask;

MaskObject::Pointer toMask(const LevelImage& li, const std::vector<std::uint8_t>& mask)
{
    auto object = MaskObject::New();
    object->set(li, mask);
    return object;
}

/// Per-parameter scales that make a unit step of each parameter move the body
/// by about the same distance (ITK divides the gradient by them): a rotation
/// of δ moves a point at radius R by R·δ, a translation of δ by δ.
Optimizer::ScalesType scalesFor(StageKind kind, double radius)
{
    const double r2 = radius * radius;
    if (kind == StageKind::Rigid) {
        Optimizer::ScalesType s(6);
        for (unsigned i = 0; i < 3; ++i) s[i] = r2;
        for (unsigned i = 3; i < 6; ++i) s[i] = 1.0;
        return s;
    }
    Optimizer::ScalesType s(12);
    for (unsigned i = 0; i < 9; ++i) s[i] = r2;
    for (unsigned i = 9; i < 12; ++i) s[i] = 1.0;
    return s;
}

using TransformBase = itk::MatrixOffsetTransformBase<double, 3, 3>;

/// Set @p xform (made by makeTransform for @p kind) to @p map with rotations about @p centre.
void assignTransform(TransformBase& xform, StageKind kind, const AffineMap& map, const Vec3d& centre)
{
    itk::Matrix<double, 3, 3> m;
    itk::Point<double, 3> c;
    itk::Vector<double, 3> t;
    const Vec3d translation = map.offset - centre + map.linear * centre;
    for (unsigned a = 0; a < 3; ++a) {
        c[a] = centre[int(a)];
        t[a] = translation[int(a)];
        for (unsigned b = 0; b < 3; ++b) m(a, b) = map.linear(int(a), int(b));
    }
    xform.SetCenter(c);
    if (kind == StageKind::Rigid) {
        static_cast<Rigid&>(xform).SetMatrix(m, 1e-6); // the start is a rotation: orthonormal to rounding
    } else {
        xform.SetMatrix(m);
    }
    xform.SetTranslation(t);
}

/// An ITK transform starting at @p map with rotations about @p centre.
TransformBase::Pointer makeTransform(StageKind kind, const AffineMap& map, const Vec3d& centre)
{
    TransformBase::Pointer xform;
    if (kind == StageKind::Rigid) {
        xform = Rigid::New();
    } else {
        xform = Affine::New();
    }
    assignTransform(*xform, kind, map, centre);
    return xform;
}

AffineMap mapOf(const itk::MatrixOffsetTransformBase<double, 3, 3>& xform)
{
    AffineMap map;
    const auto& m = xform.GetMatrix();
    const auto& o = xform.GetOffset();
    for (int a = 0; a < 3; ++a) {
        map.offset[a] = o[unsigned(a)];
        for (int b = 0; b < 3; ++b) map.linear(a, b) = m(unsigned(a), unsigned(b));
    }
    return map;
}

/// Records the metric of each iteration and the best position seen.
///
/// ITK 5.2's optimisers report an iteration after moving: GetCurrentMetricValue()
/// is the value at the position before the step, GetCurrentPosition() the one
/// after it (and ReturnBestParametersAndValue pairs them the same way, returning
/// a position one step past the best value). The observer pairs each value with
/// the position it was computed at.
class HistoryObserver : public itk::Command {
public:
    using Self = HistoryObserver;
    using Pointer = itk::SmartPointer<Self>;
    itkNewMacro(Self)
    std::vector<double>* history = nullptr;
    Optimizer::ParametersType evaluatedAt; ///< where the next reported value was computed
    Optimizer::ParametersType bestPosition;
    double bestValue = std::numeric_limits<double>::max();
    void Execute(itk::Object* caller, const itk::EventObject& event) override
    {
        Execute(static_cast<const itk::Object*>(caller), event);
    }
    void Execute(const itk::Object* caller, const itk::EventObject& event) override
    {
        if (!itk::IterationEvent().CheckEvent(&event)) return;
        const auto* opt = dynamic_cast<const Optimizer*>(caller);
        if (!opt) return;
        const double value = opt->GetCurrentMetricValue();
        if (history) history->push_back(value);
        if (value < bestValue) {
            bestValue = value;
            bestPosition = evaluatedAt;
        }
        evaluatedAt = opt->GetCurrentPosition();
    }
};

} // namespace stage

using namespace stage; // this file's own parts

struct MetricPair::Impl {
    LevelImage fixedLattice; ///< the fixed level's geometry and dims (its voxels are in `fixed`)
    ImageF::Pointer fixed, moving;
    MaskObject::Pointer movingMask;
    std::vector<std::int64_t> candidates; ///< the fixed body's voxels (dilated), for sampling, as linear indices
    int workUnits = 1;                    ///< of each metric evaluation
    double radius = 1.0;                  ///< RMS distance of the fixed body from its centroid [mm]
    Vec3d centroid = Vec3d::Zero();

    /// The index position of candidate voxel @p linear.
    Vec3d ijkOf(std::int64_t linear) const
    {
        const std::int64_t nx = fixedLattice.dims.x(), ny = fixedLattice.dims.y();
        return Vec3d(double(linear % nx), double((linear / nx) % ny), double(linear / (nx * ny)));
    }

    PointSet::Pointer samples(int count, std::uint32_t seed, bool jittered) const
    {
        auto points = PointSet::New();
        points->Initialize();
        std::mt19937 rng(seed);
        std::uniform_int_distribution<std::size_t> pick(0, candidates.size() - 1);
        std::uniform_real_distribution<double> jitter(-0.5, 0.5);
        // The samples as drawn, then in the fixed image's memory order. The
        // metric is a sum over them, so the order changes only its rounding;
        // in drawing order every sample read both images far from the last
        // one.
        std::vector<std::pair<std::int64_t, Vec3d>> drawn(std::size_t(std::max(0, count)));
        for (auto& d : drawn) {
            // The jitter, then the voxel: the draws' order since samples were
            // first drawn, so that a seed keeps its samples. Without jitter the
            // same voxels are drawn, and their centres taken.
            const double jz = jitter(rng), jy = jitter(rng), jx = jitter(rng);
            d.first = candidates[pick(rng)];
            d.second = jittered ? ijkOf(d.first) + Vec3d(jx, jy, jz) : ijkOf(d.first);
        }
        std::stable_sort(drawn.begin(), drawn.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
        points->GetPoints()->Reserve(drawn.size());
        for (std::size_t n = 0; n < drawn.size(); ++n) {
            const Vec3d w = fixedLattice.world(drawn[n].second);
            PointSet::PointType p;
            for (unsigned a = 0; a < 3; ++a) p[a] = w[int(a)];
            points->SetPoint(PointSet::PointIdentifier(n), p);
        }
        return points;
    }

    /// A metric with its transform, kept per stage setting: ITK's Mattes metric
    /// scans every voxel of both images (through their masks) for their value
    /// ranges when it is initialised, which at the finest level cost more than
    /// the optimisation itself; a pair initialises it once per setting.
    struct Prepared {
        TransformBase::Pointer xform;
        Metric::Pointer metric;
    };
    mutable std::map<std::tuple<int, int, int, std::uint32_t, bool>, Prepared> prepared;

    Prepared& prepare(const AffineMap& map, const Vec3d& centre, const StageSettings& s) const
    {
        const auto key = std::make_tuple(int(s.kind), s.samples, s.bins, s.seed, s.jittered);
        auto it = prepared.find(key);
        if (it == prepared.end()) {
            Prepared p;
            p.xform = makeTransform(s.kind, map, centre);
            p.metric = metric(p.xform.GetPointer(), s);
            it = prepared.emplace(key, std::move(p)).first;
        } else {
            assignTransform(*it->second.xform, s.kind, map, centre);
        }
        return it->second;
    }

    Metric::Pointer metric(TransformBase* xform, const StageSettings& s) const
    {
        auto m = Metric::New();
        m->SetNumberOfHistogramBins(itk::SizeValueType(s.bins));
        // The gradient images would cost a filter pass over each level per
        // stage; the metric takes central differences at the samples instead.
        m->SetUseMovingImageGradientFilter(false);
        m->SetUseFixedImageGradientFilter(false);
        m->SetFixedImage(fixed);
        m->SetMovingImage(moving);
        // No fixed mask: the samples are drawn from the fixed body (grown by
        // the margin), at its voxels' centres or jittered within them, so each
        // is inside it.
        m->SetMovingImageMask(movingMask);
        m->SetMovingTransform(xform);
        m->SetFixedSampledPointSet(samples(s.samples, s.seed, s.jittered));
        m->SetUseSampledPointSet(true);
        m->SetVirtualDomainFromImage(fixed);
        m->setWorkUnits(itk::ThreadIdType(workUnits)); // OrderedMattes: the same answer on every run
        m->Initialize();
        return m;
    }
};

MetricPair::MetricPair(
    const LevelImage& fixed, const LevelImage& moving, double marginMm, int workUnits, int movingCropVoxels)
    : mImpl(std::make_unique<Impl>())
{
    Impl& p = *mImpl;
    p.workUnits = std::max(1, workUnits);
    p.fixedLattice.geometry = fixed.geometry;
    p.fixedLattice.dims = fixed.dims;
    auto voxels = [&](const LevelImage& l) {
        return std::max(1, int(std::lround(marginMm / l.geometry.spacing.minCoeff())));
    };
    // The two images' sides are independent: side by side.
    tbb::parallel_invoke(
        [&] {
            const auto movingBody = grownBody(moving, voxels(moving));
            p.moving = movingCropVoxels < 0 ? toItk(moving) : toItkCropped(moving, movingBody, movingCropVoxels);
            p.movingMask = toMask(moving, movingBody);
        },
        [&] {
            p.fixed = toItk(fixed);
            const auto fixedBody = grownBody(fixed, voxels(fixed));
            // In index order, counted first: a torso's finest level holds millions.
            p.candidates.reserve(
                std::size_t(std::count_if(fixedBody.begin(), fixedBody.end(), [](std::uint8_t b) { return b != 0; })));
            for (std::size_t q = 0; q < fixedBody.size(); ++q) {
                if (fixedBody[q]) p.candidates.push_back(std::int64_t(q));
            }
            if (p.candidates.empty()) throw ValueError("registration: the CT has no body voxels at this level");
            Vec3d sum = Vec3d::Zero();
            for (const std::int64_t c : p.candidates) sum += fixed.world(p.ijkOf(c));
            p.centroid = sum / double(p.candidates.size());
            double r2 = 0.0;
            for (const std::int64_t c : p.candidates) r2 += (fixed.world(p.ijkOf(c)) - p.centroid).squaredNorm();
            p.radius = std::max(1.0, std::sqrt(r2 / double(p.candidates.size())));
        });
}

MetricPair::~MetricPair() = default;

double MetricPair::metricAt(const AffineMap& map, const Vec3d& centre, const StageSettings& settings) const
{
    try {
        return mImpl->prepare(map, centre, settings).metric->GetValue();
    } catch (const itk::ExceptionObject& e) {
        throw ValueError(std::string("registration: the metric cannot be evaluated here (") + e.GetDescription() + ")");
    }
}

std::pair<double, std::vector<double>> MetricPair::metricAndDerivativeAt(
    const AffineMap& map, const Vec3d& centre, const StageSettings& settings) const
{
    try {
        const Metric::Pointer metric = mImpl->prepare(map, centre, settings).metric;
        Metric::MeasureType value = 0;
        Metric::DerivativeType derivative;
        metric->GetValueAndDerivative(value, derivative);
        return {value, std::vector<double>(derivative.begin(), derivative.end())};
    } catch (const itk::ExceptionObject& e) {
        throw ValueError(std::string("registration: the metric cannot be evaluated here (") + e.GetDescription() + ")");
    }
}

StageResult MetricPair::run(const AffineMap& start, const Vec3d& centre, const StageSettings& settings) const
{
    StageResult r;
    TransformBase::Pointer xform;
    try {
        Impl::Prepared& prepared = mImpl->prepare(start, centre, settings);
        xform = prepared.xform;
        const Metric::Pointer metric = prepared.metric;
        r.startMetric = metric->GetValue();
        auto opt = Optimizer::New();
        opt->SetNumberOfWorkUnits(1);
        opt->SetMetric(metric);
        opt->SetScales(scalesFor(settings.kind, mImpl->radius));
        opt->SetLearningRate(settings.stepMm);
        opt->SetMinimumStepLength(settings.minimumStepMm);
        opt->SetRelaxationFactor(settings.relaxation);
        opt->SetGradientMagnitudeTolerance(1e-12);
        opt->SetNumberOfIterations(itk::SizeValueType(settings.iterations));
        opt->SetDoEstimateLearningRateAtEachIteration(false);
        opt->SetDoEstimateLearningRateOnce(false);
        auto observer = HistoryObserver::New();
        observer->history = &r.history;
        observer->evaluatedAt = xform->GetParameters();
        opt->AddObserver(itk::IterationEvent(), observer);
        opt->StartOptimization();
        r.iterations = int(opt->GetCurrentIteration());
        r.hitIterationLimit =
            opt->GetStopCondition() == itk::StopConditionObjectToObjectOptimizerEnum::MAXIMUM_NUMBER_OF_ITERATIONS;
        r.stopReason = opt->GetStopConditionDescription();
        // The last position, then the best the observer saw (the start included).
        r.finalMetric = metric->GetValue();
        if (observer->bestValue < r.finalMetric) {
            metric->SetParameters(observer->bestPosition);
            r.finalMetric = observer->bestValue;
        }
    } catch (const itk::ExceptionObject& e) {
        throw ValueError(std::string("registration: the optimiser failed (") + e.GetDescription() + ")");
    }
    r.map = mapOf(*xform);
    return r;
}

} // namespace voxhap::registration::detail
