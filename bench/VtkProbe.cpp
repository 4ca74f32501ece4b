// SPDX-License-Identifier: Apache-2.0
/// @file VtkProbe.cpp
/// @brief vtkProbeFilter line probing.

#include "bench/VtkProbe.h"

#include <vtkDataArray.h>
#include <vtkFloatArray.h>
#include <vtkImageData.h>
#include <vtkLineSource.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkProbeFilter.h>

#include <cmath>

namespace voxhap::bench {

struct VtkProbe::Impl {
    vtkNew<vtkImageData> image;
    vtkNew<vtkFloatArray> values;
    vtkNew<vtkLineSource> line;
    vtkNew<vtkProbeFilter> probe;
};

VtkProbe::VtkProbe(const DenseField& dense) : mImpl(std::make_unique<Impl>())
{
    Impl& m = *mImpl;
    m.image->SetDimensions(dense.dims().x(), dense.dims().y(), dense.dims().z());
    m.image->SetSpacing(dense.spacing().data());
    m.image->SetOrigin(dense.worldOrigin().data());
    // Share the dense buffer: save = 1 tells VTK not to free it.
    m.values->SetArray(const_cast<float*>(dense.values().data()), vtkIdType(dense.values().size()), 1);
    m.values->SetName("beta");
    m.image->GetPointData()->SetScalars(m.values);
    m.probe->SetInputConnection(m.line->GetOutputPort());
    m.probe->SetSourceData(m.image);
}

VtkProbe::~VtkProbe() = default;

double VtkProbe::integrate(const haptic::Segment& s, double stepMm)
{
    Impl& m = *mImpl;
    const double length = (s.tip - s.entry).norm();
    if (!(length > 0.0)) return 0.0;
    const int n = std::max(1, int(std::ceil(length / stepMm)));
    m.line->SetPoint1(s.entry.data());
    m.line->SetPoint2(s.tip.data());
    m.line->SetResolution(n);
    m.probe->Update();
    vtkDataArray* out = m.probe->GetOutput()->GetPointData()->GetArray("beta");
    if (!out) return 0.0;
    double sum = 0.0;
    for (vtkIdType i = 0; i <= n; ++i) sum += (i == 0 || i == n ? 0.5 : 1.0) * out->GetTuple1(i);
    return sum * length / double(n);
}

} // namespace voxhap::bench
