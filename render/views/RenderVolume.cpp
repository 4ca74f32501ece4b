// SPDX-License-Identifier: Apache-2.0
/// @file RenderVolume.cpp
/// @brief The one dense copy of a volume's grids for VTK, and slices resampled
/// from it with vtkImageReslice (no GL: this is the display-free path).
#include "render/detail/VtkVolume.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tools/Count.h> // for minMax
#include <openvdb/tools/Dense.h>

#include <vtkFloatArray.h>
#include <vtkImageReslice.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkShortArray.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>

namespace voxhap::render {

namespace {

/// Copy @p grid over @p box straight into a new VTK array (x fastest, VTK's
/// layout): the only copy of the voxels the views make.
template <typename VtkArray, typename Grid>
vtkSmartPointer<vtkImageData> denseCopy(const Grid& grid, const volume::IndexBox& box, const Vec3d& spacing)
{
    using Value = typename VtkArray::ValueType;
    auto img = vtkSmartPointer<vtkImageData>::New();
    img->SetExtent(box.min.x(), box.max.x(), box.min.y(), box.max.y(), box.min.z(), box.max.z());
    img->SetSpacing(spacing.x(), spacing.y(), spacing.z());
    img->SetOrigin(0.0, 0.0, 0.0);
    auto values = vtkSmartPointer<VtkArray>::New();
    values->SetNumberOfComponents(1);
    values->SetNumberOfTuples(box.voxelCount());
    img->GetPointData()->SetScalars(values);
    openvdb::tools::Dense<Value, openvdb::tools::LayoutXYZ> dense(volume::toCoordBBox(box), values->GetPointer(0));
    openvdb::tools::copyToDense(grid, dense); // parallel (TBB)
    return img;
}

/// Resample @p img on the plane of @p f: output pixel (x, y) is the world point
/// f.toWorld(x, y), mapped into the arrays' data coordinates.
template <typename T>
std::vector<T> reslice(
    vtkImageData* img, const RenderVolume::Impl& v, const ViewFrame& f, bool linear, double background)
{
    // Data coordinates are millimetres along the index axes: data = D⁻¹ (world − origin).
    const Mat3d toData = v.direction.inverse();
    const Vec3d columns[4] = {toData * f.right, toData * f.down, toData * f.normal, toData * (f.origin - v.origin)};
    vtkNew<vtkMatrix4x4> axes;
    for (int c = 0; c < 4; ++c) {
        for (int r = 0; r < 3; ++r) axes->SetElement(r, c, columns[c][r]);
    }
    vtkNew<vtkImageReslice> reslice;
    reslice->SetInputData(img);
    reslice->SetResliceAxes(axes);
    reslice->SetOutputDimensionality(2);
    reslice->SetOutputOrigin(0.0, 0.0, 0.0);
    reslice->SetOutputSpacing(f.pixelMm, f.pixelMm, 1.0);
    reslice->SetOutputExtent(0, f.width - 1, 0, f.height - 1, 0, 0);
    if (linear)
        reslice->SetInterpolationModeToLinear();
    else
        reslice->SetInterpolationModeToNearestNeighbor();
    reslice->SetBackgroundLevel(background);
    reslice->Update();
    const auto* p = static_cast<const T*>(reslice->GetOutput()->GetScalarPointer());
    return std::vector<T>(p, p + std::size_t(f.width) * std::size_t(f.height));
}

/// The kBodyLowPercentile and kBodyHighPercentile of @p grid's active voxels
/// (a tile counts as all its voxels); [lo, hi] if none is active. From a
/// histogram of kPercentileBins bins over the active values' range, as VTK's
/// vtkImageHistogramStatistics bins float data (65536 bins): exact to half a
/// bin, without a copy of the values (an MR volume may hold tens of millions).
std::array<double, 2> activePercentiles(const volume::FloatGrid& grid, double lo, double hi)
{
    constexpr int kPercentileBins = 1 << 16;
    double a = std::numeric_limits<double>::infinity(), b = -a;
    std::int64_t n = 0;
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        if (!std::isfinite(*it)) continue;
        a = std::min(a, double(*it)), b = std::max(b, double(*it));
        n += std::int64_t(it.getVoxelCount());
    }
    if (n == 0) return {lo, hi};
    if (!(b > a)) return {a, a};
    const double scale = kPercentileBins / (b - a);
    std::vector<std::int64_t> histogram(kPercentileBins, 0);
    for (auto it = grid.cbeginValueOn(); it; ++it) {
        if (!std::isfinite(*it)) continue;
        histogram[std::size_t(std::min(kPercentileBins - 1, int((*it - a) * scale)))] +=
            std::int64_t(it.getVoxelCount());
    }
    const auto at = [&](double percent) {
        const auto rank =
            std::int64_t(std::floor(percent / 100.0 * double(n - 1))); // 0-based, as a sorted array's index
        std::int64_t seen = 0;
        for (int bin = 0; bin < kPercentileBins; ++bin) {
            seen += histogram[std::size_t(bin)];
            if (seen > rank) return std::clamp(a + (bin + 0.5) / scale, a, b);
        }
        return b;
    };
    return {at(kBodyLowPercentile), at(kBodyHighPercentile)};
}

} // namespace

std::string_view scalarUnits(ScalarChannel c)
{
    switch (c) {
    case ScalarChannel::Hu:
        return "HU";
    case ScalarChannel::T1:
        return "ms";
    case ScalarChannel::Intensity:
        return "a.u.";
    }
    return "?";
}

std::string windowLegend(ScalarChannel c, const WindowLevel& w)
{
    const char* name = c == ScalarChannel::Hu ? "CT" : c == ScalarChannel::T1 ? "T1" : "MR";
    const auto number = [](double x) {
        std::ostringstream os;
        os << std::setprecision(x != 0.0 && std::abs(x) < 10.0 ? 2 : 0) << std::fixed << x;
        return os.str();
    };
    return std::string(name) + " " + number(w.level - 0.5 * w.width) + ".." + number(w.level + 0.5 * w.width) + " " +
        std::string(scalarUnits(c));
}

vtkSmartPointer<vtkMatrix4x4> RenderVolume::Impl::dataToWorld() const
{
    auto m = vtkSmartPointer<vtkMatrix4x4>::New();
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) m->SetElement(r, c, direction(r, c));
        m->SetElement(r, 3, origin[r]);
    }
    return m;
}

RenderVolume::RenderVolume(const volume::Volume& v, bool withLabels) : mImpl(std::make_unique<Impl>())
{
    volume::initializeOpenVdb();
    Impl& d = *mImpl;
    const volume::IndexBox& box = v.indexBox();
    if (box.empty()) throw ValueError("render: the volume is empty");
    const volume::Geometry g = v.geometry();
    d.direction = g.direction;
    d.origin = g.origin;
    d.spacing = g.spacing;
    const auto wb = v.worldBounds();
    d.bounds = {wb[0], wb[1]};

    volume::FloatGrid::ConstPtr image = volume::huGrid(v);
    d.channel = ScalarChannel::Hu;
    if (!image) {
        image = volume::t1Grid(v);
        d.channel = ScalarChannel::T1;
    }
    if (!image) {
        image = volume::intensityGrid(v);
        d.channel = ScalarChannel::Intensity;
    }
    if (!image) throw ValueError("render: the volume has no hu, t1 or intensity grid");
    d.background = image->background();
    d.scalars = denseCopy<vtkFloatArray>(*image, box, g.spacing);

    // Range, and the mean above the background for the summed projection.
    auto* values = static_cast<vtkFloatArray*>(d.scalars->GetPointData()->GetScalars());
    const float* p = values->GetPointer(0);
    const std::size_t n = std::size_t(box.voxelCount());
    double lo = std::numeric_limits<double>::max(), hi = -lo, sum = 0.0;
    std::size_t tissue = 0;
    for (std::size_t i = 0; i < n; ++i) {
        const double x = p[i];
        lo = std::min(lo, x), hi = std::max(hi, x);
        if (x > d.background) sum += x, ++tissue;
    }
    d.lo = lo, d.hi = hi;
    d.tissueMean = tissue ? sum / double(tissue) : hi;
    d.bodyRange = d.channel == ScalarChannel::Hu ? std::array<double, 2>{lo, hi} : activePercentiles(*image, lo, hi);

    if (withLabels) {
        if (const volume::LabelGrid::ConstPtr labels = volume::labelGrid(v)) {
            const auto ids = openvdb::tools::minMax(labels->tree()); // active values; cheap on a sparse grid
            if (ids.min() < 0 || ids.max() > std::numeric_limits<short>::max()) {
                throw ValueError(
                    "render: tissue labels outside 0.." + std::to_string(std::numeric_limits<short>::max()));
            }
            d.labels = denseCopy<vtkShortArray>(*labels, box, g.spacing);
        }
    }
}

RenderVolume::~RenderVolume() = default;

ScalarChannel RenderVolume::channel() const { return mImpl->channel; }
bool RenderVolume::hasLabels() const { return mImpl->labels != nullptr; }
WorldBounds RenderVolume::worldBounds() const { return mImpl->bounds; }
double RenderVolume::finestSpacing() const { return mImpl->spacing.minCoeff(); }
double RenderVolume::scalarMin() const { return mImpl->lo; }
double RenderVolume::scalarMax() const { return mImpl->hi; }
double RenderVolume::tissueMean() const { return mImpl->tissueMean; }
std::array<double, 2> RenderVolume::bodyRange() const { return mImpl->bodyRange; }

WindowLevel RenderVolume::defaultWindow(BlendMode mode) const
{
    if (mImpl->channel == ScalarChannel::Hu) {
        return windowLevel(mode == BlendMode::Mip ? WindowPreset::Bone : WindowPreset::SoftTissue);
    }
    const auto [lo, hi] = mImpl->bodyRange;
    // A body of one value (a phantom block) still needs a ramp: a width of one unit.
    const double width = hi > lo ? hi - lo : 1.0;
    return {width, hi > lo ? 0.5 * (lo + hi) : lo};
}

std::size_t RenderVolume::denseBytes() const
{
    std::size_t bytes = std::size_t(mImpl->scalars->GetPointData()->GetScalars()->GetActualMemorySize()) * 1024;
    if (mImpl->labels) bytes += std::size_t(mImpl->labels->GetPointData()->GetScalars()->GetActualMemorySize()) * 1024;
    return bytes;
}

std::vector<float> RenderVolume::sliceValues(const ViewFrame& f) const
{
    return reslice<float>(mImpl->scalars, *mImpl, f, true, mImpl->background);
}

std::vector<std::int32_t> RenderVolume::sliceLabels(const ViewFrame& f) const
{
    if (!mImpl->labels) return {};
    const std::vector<short> ids = reslice<short>(mImpl->labels, *mImpl, f, false, 0.0);
    return std::vector<std::int32_t>(ids.begin(), ids.end());
}

} // namespace voxhap::render
