// SPDX-License-Identifier: Apache-2.0
/// @file FusionBindings.cpp
/// @brief Python: one patient's CT and MR fused into one volume, as `voxhap
/// fuse` does (fusion/PatientFusion.h; docs/reference.md "CT and MR fusion").

#include "python/Bindings.h"

#include "fusion/PatientFusion.h"
#include "haptic/materials/MaterialField.h"

#include <nlohmann/json.hpp>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <optional>

namespace voxhap::python {

void bindFusion(py::module_& m)
{
    m.def(
        "fuse",
        [](const std::filesystem::path& ct, const std::filesystem::path& mr, std::optional<std::filesystem::path> out,
            bool affine, const std::string& start, const std::string& ctSeries, const std::string& mrSeries,
            std::size_t mrVolume, bool differentPatients) {
            fusion::PatientFusionOptions o;
            o.ct = ct;
            o.mr = mr;
            o.ctLoad.dicom.series = ctSeries;
            o.mrLoad.dicom.series = mrSeries;
            o.mrLoad.dicom.volume = mrVolume;
            o.registration.affine = affine;
            if (start == "auto") {
                o.start = fusion::Start::Auto;
            } else if (start == "search") {
                o.start = fusion::Start::Search;
            } else if (start == "geometry") {
                o.start = fusion::Start::Geometry;
            } else {
                throw ValueError("start='" + start + "': expected 'auto', 'search' or 'geometry'");
            }
            o.differentPatients = differentPatients;
            if (out && out->extension() != ".vdb") {
                throw ValueError("out='" + out->string() + "': expected a .vdb file name");
            }
            std::shared_ptr<volume::Volume> fused;
            haptic::DampingSources sources;
            {
                py::gil_scoped_release release;
                fusion::PatientFusion f = fusion::fusePatient(o);
                if (out) fusion::writeFusion(f, *out);
                haptic::MaterialOptions mo;
                mo.needs.damping = true;
                sources = haptic::MaterialField(f.volume, volume::TissueTable::builtin(), mo).dampingSources();
                fused = std::make_shared<volume::Volume>(std::move(f.volume));
            }
            py::dict d;
            d["volume"] = fused;
            d["record"] = toPython(volume::toJson(*fused->metadata().fusion));
            d["damping_from_t1_fraction"] = sources.t1Fraction();
            return d;
        },
        py::arg("ct"), py::arg("mr"), py::kw_only(), py::arg("out") = std::nullopt, py::arg("affine") = false,
        py::arg("start") = "auto", py::arg("ct_series") = "", py::arg("mr_series") = "", py::arg("mr_volume") = 0,
        py::arg("different_patients") = false,
        "Register the patient's MR onto their CT and return {'volume': the fused Volume on the CT's grid (hu, "
        "the MR as t1 or intensity, labels from both), 'record': the registration record (mr_from_ct 4x4 LPS, "
        "metrics, iterations, stop reason, overlap, warnings, channel sources), 'damping_from_t1_fraction'}, "
        "as `voxhap fuse`. out= also writes the .vdb and the ITK .tfm beside it. start: 'auto', 'search' or "
        "'geometry'. Raises ValueError or OSError with the command line's one-line refusal.");
}

} // namespace voxhap::python
