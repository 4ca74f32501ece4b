// SPDX-License-Identifier: Apache-2.0
/// @file ModalityInference.cpp
/// @brief Value census of a raw grid and the CT/MR rule.

#include "volume/io/ModalityInference.h"

#include "core/Errors.h"
#include "volume/Grids.h"

#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <limits>
#include <sstream>

namespace voxhap::volume {

namespace {

struct Census {
    double count = 0, air = 0, water = 0, negative = 0;
    double lo = std::numeric_limits<double>::infinity(), hi = -std::numeric_limits<double>::infinity();
    void add(double v, double n)
    {
        count += n;
        if (v >= -1200.0 && v <= -900.0) air += n;
        if (v >= -200.0 && v <= 200.0) water += n;
        if (v < 0) negative += n;
        lo = std::min(lo, v), hi = std::max(hi, v);
    }
    void join(const Census& o)
    {
        count += o.count, air += o.air, water += o.water, negative += o.negative;
        lo = std::min(lo, o.lo), hi = std::max(hi, o.hi);
    }
};

std::string percent(double f)
{
    std::ostringstream os;
    os.precision(3);
    os << 100.0 * f << " %";
    return os.str();
}

std::string number(double v)
{
    std::ostringstream os;
    os.precision(6);
    os << v;
    return os.str();
}

} // namespace

ModalityGuess inferModality(const openvdb::GridBase& base)
{
    const auto* grid = dynamic_cast<const FloatGrid*>(&base);
    if (!grid) throw ValueError("inferModality: not a float grid");
    Census c;
    // Tiles count with their voxel count; leaves voxel by voxel, in parallel.
    for (auto it = grid->tree().cbeginValueOn(); it; ++it) {
        if (!it.isVoxelValue()) c.add(*it, double(it.getVoxelCount()));
    }
    openvdb::tree::LeafManager<const FloatGrid::TreeType> leaves(grid->tree());
    const Census fromLeaves = tbb::parallel_reduce(
        leaves.leafRange(), Census{},
        [](const auto& range, Census acc) {
            for (auto leaf = range.begin(); leaf; ++leaf) {
                for (auto v = leaf->cbeginValueOn(); v; ++v) acc.add(*v, 1.0);
            }
            return acc;
        },
        [](Census a, const Census& b) {
            a.join(b);
            return a;
        });
    c.join(fromLeaves);
    ModalityGuess g;
    if (c.count == 0) {
        g.reason = "no voxel to go by";
        return g;
    }
    const double air = c.air / c.count, water = c.water / c.count;
    const std::string range = "values " + number(c.lo) + " to " + number(c.hi);
    if (c.lo >= 0.0) {
        g.kind = ModalityGuess::Kind::Mr;
        g.reason = "no negative value (" + range + "): magnitude MR intensities, not CT in HU (whose air is -1000)";
    } else if (air >= kMinAirFraction && water >= kMinWaterFraction) {
        g.kind = ModalityGuess::Kind::Ct;
        g.reason = percent(air) + " of the voxels at -1200..-900 (air in HU) and " + percent(water) +
            " at -200..200 (water, soft tissue): CT in HU (" + range + ")";
    } else if (c.hi > 0 && -c.lo <= kMaxRingingFraction * c.hi && air == 0) {
        g.kind = ModalityGuess::Kind::Mr;
        g.reason = "negative values only down to " + number(c.lo) + ", within " + percent(kMaxRingingFraction) +
            " of the maximum " + number(c.hi) + " (interpolation ringing): MR intensities";
    } else {
        g.reason = "negative values (" + range + ", " + percent(c.negative / c.count) +
            " below 0) without the air of a CT (" + percent(air) +
            " at -1200..-900): neither CT in HU nor magnitude MR";
    }
    return g;
}

} // namespace voxhap::volume
