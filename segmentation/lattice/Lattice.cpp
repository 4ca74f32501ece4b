// SPDX-License-Identifier: Apache-2.0
/// @file Lattice.cpp
/// @brief Lattice of a volume's index box.

#include "segmentation/lattice/Lattice.h"

#include <cmath>

namespace voxhap::segmentation {

Lattice Lattice::of(const volume::Volume& v)
{
    Lattice l;
    const volume::IndexBox& box = v.indexBox();
    l.dims = box.dims();
    l.origin = box.min;
    const volume::Geometry g = v.geometry();
    l.spacing = g.spacing;
    // Slices are cut across the patient's long axis (LPS z), whatever the index
    // order of the file: per-slice operations (hole filling, the skin shell) follow it.
    int best = 2;
    for (int a = 0; a < 3; ++a) {
        if (std::abs(g.direction(2, a)) > std::abs(g.direction(2, best))) best = a;
    }
    l.sliceAxis = best;
    return l;
}

} // namespace voxhap::segmentation
