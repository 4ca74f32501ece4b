// SPDX-License-Identifier: Apache-2.0
/// @file VtkProbe.h
/// @brief The VTK user's baseline: vtkProbeFilter over a vtkLineSource on a
/// vtkImageData that shares the dense array (no copy).
#pragma once

#include "bench/DenseField.h"

#include <memory>

namespace voxhap::bench {

class VtkProbe {
public:
    explicit VtkProbe(const DenseField& dense);
    ~VtkProbe();
    /// @brief ∫β ds from trilinear probes every ≤ stepMm, trapezoid rule [N·s/mm].
    double integrate(const haptic::Segment& s, double stepMm);

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace voxhap::bench
