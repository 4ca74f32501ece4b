// SPDX-License-Identifier: Apache-2.0
/// @file VolumeBindings.cpp
/// @brief Python: Volume with its grids as numpy arrays and the 4x4
/// index-to-world transform, load and save, phantoms, the tissue table.

#include "python/Bindings.h"

#include "core/Errors.h"
#include "phantoms/Phantoms.h"
#include "volume/Grids.h"
#include "volume/TissueTable.h"
#include "volume/VolumeFile.h"

#include <nlohmann/json.hpp>
#include <openvdb/tools/Dense.h> // copyToDense, copyFromDense
#include <pybind11/eigen.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::python {

namespace {

using volume::Channel;
using volume::Volume;
using Mat4d = Eigen::Matrix4d;

std::optional<Channel> channelOf(const std::string& name)
{
    for (Channel c : volume::kChannels) {
        if (volume::channelName(c) == name) return c;
    }
    return std::nullopt;
}

/// The array of a grid over the box: Dense's ZYX layout has k fastest, i.e. a
/// C-ordered numpy array indexed [i, j, k].
template <typename GridT> py::array denseOf(const GridT& grid, const volume::IndexBox& box)
{
    using ValueT = typename GridT::ValueType;
    const Vec3i d = box.dims();
    py::array_t<ValueT> out({py::ssize_t(d.x()), py::ssize_t(d.y()), py::ssize_t(d.z())});
    if (box.empty()) return out;
    openvdb::tools::Dense<ValueT, openvdb::tools::LayoutZYX> dense(volume::toCoordBBox(box), out.mutable_data());
    openvdb::tools::copyToDense(grid, dense);
    return out;
}

template <typename GridT>
typename GridT::Ptr sparseOf(const py::array& any, const volume::IndexBox& box, typename GridT::ValueType background)
{
    using ValueT = typename GridT::ValueType;
    const auto a = py::array_t<ValueT, py::array::c_style | py::array::forcecast>::ensure(any);
    if (!a) throw ValueError("grid: the array cannot be converted to the grid's value type");
    auto grid = GridT::create(background);
    openvdb::tools::Dense<const ValueT, openvdb::tools::LayoutZYX> dense(volume::toCoordBBox(box), a.data());
    // Voxels equal to the background (air) stay inactive, as every reader leaves them.
    openvdb::tools::copyFromDense(dense, *grid, ValueT(0));
    return grid;
}

void checkShape(const py::array& a, const Volume& v, const std::string& name)
{
    const Vec3i d = v.indexBox().dims();
    if (a.ndim() != 3 || a.shape(0) != d.x() || a.shape(1) != d.y() || a.shape(2) != d.z()) {
        throw ValueError("grid '" + name + "': expected an array of shape (" + std::to_string(d.x()) + ", " +
            std::to_string(d.y()) + ", " + std::to_string(d.z()) + "), the volume's shape");
    }
}

/// Array index (a, b, c) of voxel ijk = min + (a, b, c) → world: the 4x4 affine.
Mat4d arrayToWorld(const Volume& v)
{
    const volume::Geometry g = v.geometry();
    const Mat3d m = g.direction * g.spacing.asDiagonal();
    Mat4d out = Mat4d::Identity();
    out.topLeftCorner<3, 3>() = m;
    out.topRightCorner<3, 1>() = g.origin + m * v.indexBox().min.cast<double>();
    return out;
}

/// The Geometry of a 4x4 affine: spacing the column norms, direction the unit columns.
volume::Geometry geometryOfAffine(const Mat4d& a)
{
    if (!a.allFinite() || (a.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-12)
        throw ValueError("index_to_world: expected a finite 4x4 affine matrix with last row 0, 0, 0, 1");
    volume::Geometry g;
    for (int c = 0; c < 3; ++c) {
        g.spacing[c] = a.block<3, 1>(0, c).norm();
        if (!(g.spacing[c] > 0)) throw ValueError("index_to_world: column " + std::to_string(c) + " is zero");
        g.direction.col(c) = a.block<3, 1>(0, c) / g.spacing[c];
    }
    g.origin = a.block<3, 1>(0, 3);
    return g; // makeTransform checks that the columns are unit and independent
}

std::shared_ptr<Volume> makeVolume(const std::array<int, 3>& shape, const Mat4d& affine)
{
    for (int n : shape) {
        if (n < 1) throw ValueError("shape: every dimension must be at least 1");
    }
    volume::IndexBox box{Vec3i(0, 0, 0), Vec3i(shape[0] - 1, shape[1] - 1, shape[2] - 1)};
    return std::make_shared<Volume>(geometryOfAffine(affine), box);
}

void setGrid(Volume& v, const std::string& name, const py::array& a)
{
    checkShape(a, v, name);
    const std::optional<Channel> c = channelOf(name);
    const volume::IndexBox& box = v.indexBox();
    if (c == Channel::Label) {
        v.setGrid(*c, sparseOf<volume::LabelGrid>(a, box, volume::kAirLabel));
    } else if (c) {
        const float air = *c == Channel::Hu ? volume::kAirHu
            : *c == Channel::T1             ? volume::kAirT1
                                            : volume::kAirIntensity;
        v.setGrid(*c, sparseOf<volume::FloatGrid>(a, box, air));
    } else {
        v.setDerived(name, sparseOf<volume::FloatGrid>(a, box, 0.0f));
    }
}

py::dict metadataOf(const Volume& v)
{
    const auto& m = v.metadata();
    py::dict d;
    d["modality"] = m.modality;
    d["source"] = m.source;
    d["description"] = m.description;
    d["mr_weighting"] = ""; // CT and phantoms
    // The typed facts under their names (docs/reference.md "Volume metadata"), as text.
    for (const auto& [name, text] : volume::metadataFacts(m)) d[py::str(name)] = text;
    // A fused volume's record as the dict json.loads gives, not as its text.
    if (m.fusion) d["fusion"] = toPython(volume::toJson(*m.fusion));
    py::dict extra;
    for (const auto& [k, value] : m.extra) extra[py::str(k)] = value;
    d["extra"] = extra;
    return d;
}

py::object phantomLayersOf(const Volume& v)
{
    const auto layers = volume::phantomLayers(v);
    if (!layers) return py::none();
    py::dict d;
    d["entry"] = layers->entry;
    d["direction"] = layers->direction;
    py::list rows;
    for (const auto& l : layers->layers) {
        py::dict r;
        r["tissue"] = l.name;
        r["label"] = l.tissue;
        r["start_mm"] = l.startMm;
        r["end_mm"] = l.endMm;
        rows.append(r);
    }
    d["layers"] = rows;
    return d;
}

py::dict tissueDict(const volume::Tissue& t)
{
    py::dict d;
    d["id"] = t.id;
    d["name"] = t.name;
    d["description"] = t.description;
    d["critical"] = t.critical;
    d["rigid"] = t.rigid;
    d["hu_min"] = t.huMin;
    d["hu_typical"] = t.huTypical;
    d["hu_max"] = t.huMax;
    d["t1_1p5t_ms"] = t.t1At1p5T.value;
    d["t1_3t_ms"] = t.t1At3T.value;
    const auto opt = [](const std::optional<volume::Quantity>& q) -> py::object {
        return q ? py::object(py::float_(q->value)) : py::none();
    };
    d["thickness_mm"] = opt(t.thickness);
    d["puncture_force_N"] = opt(t.punctureForce);
    d["cutting_force_N"] = opt(t.cuttingForce);
    d["elasticity_N_per_mm"] = opt(t.elasticity);
    d["friction_viscous_Ns_per_mm2"] = opt(t.frictionViscous);
    d["friction_coulomb_N"] = opt(t.frictionCoulomb);
    d["damping_Ns_per_mm2"] = opt(t.damping);
    return d;
}

volume::DeclaredModality modalityOf(const std::string& s)
{
    if (s == "infer") return volume::DeclaredModality::Infer;
    if (s == "ct" || s == "CT") return volume::DeclaredModality::Ct;
    if (s == "mr" || s == "MR") return volume::DeclaredModality::Mr;
    throw ValueError("modality: expected 'infer', 'ct' or 'mr', got '" + s + "'");
}

} // namespace

py::array gridToArray(const Volume& v, const openvdb::GridBase& grid)
{
    if (const auto* f = dynamic_cast<const volume::FloatGrid*>(&grid)) return denseOf(*f, v.indexBox());
    if (const auto* l = dynamic_cast<const volume::LabelGrid*>(&grid)) return denseOf(*l, v.indexBox());
    throw ValueError("grid '" + grid.getName() + "': neither float nor int32");
}

void bindVolume(py::module_& m)
{
    py::class_<Volume, std::shared_ptr<Volume>>(m, "Volume",
        "Named grids (hu, t1, label, intensity and derived ones such as sdf.kidney) over one index box, "
        "sharing one index-to-world transform, with metadata. World space is patient LPS in mm.")
        .def(py::init(&makeVolume), py::arg("shape"), py::arg("index_to_world") = Mat4d::Identity(),
            "An empty volume of the given shape (ni, nj, nk) and 4x4 index-to-world affine (columns: the world "
            "step of one voxel along i, j, k [mm]; last column: the world position of voxel [0, 0, 0]'s centre)")
        .def_property_readonly("shape",
            [](const Volume& v) {
                const Vec3i d = v.indexBox().dims();
                return py::make_tuple(d.x(), d.y(), d.z());
            })
        .def_property_readonly(
            "index_to_world", &arrayToWorld, "4x4 affine from an array index [a, b, c] (voxel centres) to world LPS mm")
        .def_property_readonly(
            "index_min",
            [](const Volume& v) {
                const Vec3i& i = v.indexBox().min;
                return py::make_tuple(i.x(), i.y(), i.z());
            },
            "voxhap's own index of array element [0, 0, 0] (OpenVDB coordinates)")
        .def_property_readonly("spacing", [](const Volume& v) { return Vec3d(v.geometry().spacing); })
        .def_property_readonly(
            "world_bounds",
            [](const Volume& v) {
                const auto b = v.worldBounds();
                return py::make_tuple(b[0], b[1]);
            },
            "(min, max) world corners of the box, voxel faces included [mm]")
        .def_property_readonly("channels",
            [](const Volume& v) {
                std::vector<std::string> out;
                for (Channel c : volume::kChannels) {
                    if (v.has(c)) out.emplace_back(volume::channelName(c));
                }
                return out;
            })
        .def_property_readonly("derived_names",
            [](const Volume& v) {
                std::vector<std::string> out;
                for (const auto& [name, grid] : v.derivedGrids()) out.push_back(name);
                return out;
            })
        .def(
            "grid",
            [](const Volume& v, const std::string& name) {
                const std::optional<Channel> c = channelOf(name);
                const Volume::GridConstPtr g = c ? v.grid(*c) : v.derived(name);
                if (!g) throw py::key_error("the volume has no grid '" + name + "'");
                return gridToArray(v, *g);
            },
            py::arg("name"),
            "The grid as a new numpy array of the volume's shape (float32; label int32); air where inactive")
        .def("set_grid", &setGrid, py::arg("name"), py::arg("array"),
            "Store an array of the volume's shape as a grid (hu, t1, intensity: float; label: int32; any other "
            "name: a derived float grid). Voxels equal to the air value stay inactive.")
        .def("__contains__",
            [](const Volume& v, const std::string& name) {
                const std::optional<Channel> c = channelOf(name);
                return c ? v.has(*c) : v.derived(name) != nullptr;
            })
        .def_property_readonly("metadata", &metadataOf)
        .def_property(
            "modality", [](const Volume& v) { return v.metadata().modality; },
            [](Volume& v, const std::string& s) { v.metadata().modality = s; })
        .def_property(
            "description", [](const Volume& v) { return v.metadata().description; },
            [](Volume& v, const std::string& s) { v.metadata().description = s; })
        .def("phantom_layers", &phantomLayersOf,
            "A phantom's layer table along its reference path: {entry, direction, layers: [{tissue, label, "
            "start_mm, end_mm}]}, or None")
        .def(
            "landmark",
            [](const Volume& v, const std::string& name) -> py::object {
                const auto p = volume::phantomLandmark(v, name);
                return p ? py::cast(*p) : py::none();
            },
            py::arg("name"), "A phantom's named point [mm], e.g. 'entry', 'target', or None")
        .def(
            "copy", [](const Volume& v) { return std::make_shared<Volume>(v); },
            "A copy that shares the (immutable) grids: setting a grid on one leaves the other as it was")
        .def("__repr__", [](const Volume& v) {
            const Vec3i d = v.indexBox().dims();
            std::string ch;
            for (Channel c : volume::kChannels) {
                if (v.has(c)) ch += (ch.empty() ? "" : ", ") + std::string(volume::channelName(c));
            }
            return "<voxhap.Volume " + std::to_string(d.x()) + "x" + std::to_string(d.y()) + "x" +
                std::to_string(d.z()) + " " + v.metadata().modality + " [" + ch + "]>";
        });

    m.def(
        "load",
        [](const std::filesystem::path& path, const std::string& modality, const std::string& series,
            std::size_t volumeIndex) {
            volume::LoadOptions o;
            o.modality = modalityOf(modality);
            o.dicom.series = series;
            o.dicom.volume = volumeIndex;
            py::gil_scoped_release release;
            return std::make_shared<Volume>(volume::loadVolume(path, o));
        },
        py::arg("path"), py::arg("modality") = "infer", py::arg("series") = "", py::arg("volume") = 0,
        "Load a volume: DICOM folder or file, .nii/.nii.gz, .nrrd, .mha/.mhd or .vdb. modality: 'infer', 'ct' "
        "or 'mr' for formats that do not say. A DICOM folder: series= its UID, SeriesNumber or '#index' (the "
        "command line's --series; default the largest), volume= which volume of a 4D series from 1 (--volume; "
        "0: the series must hold one). Raises OSError naming the file and field.");
    m.def(
        "save",
        [](const Volume& v, const std::filesystem::path& path) {
            py::gil_scoped_release release;
            volume::saveVolume(v, path);
        },
        py::arg("volume"), py::arg("path"), "Save to .vdb (every grid) or .nrrd (hu, else t1, else label)");

    m.def(
        "phantom",
        [](const std::string& kind, double spacing, const std::string& preset, std::optional<double> bmi,
            std::optional<std::vector<std::pair<std::string, double>>> layers, double tiltDeg, double radiusMm,
            double lesionRadiusMm, const std::string& field) {
            const volume::TissueTable& table = volume::TissueTable::builtin();
            volume::PhantomSpec spec;
            spec.kind = kind;
            if (layers) {
                spec.slab.layers.clear();
                for (const auto& [tissue, mm] : *layers) spec.slab.layers.push_back({tissue, mm});
            }
            spec.slab.tiltDeg = tiltDeg;
            spec.sphere.radiusMm = radiusMm;
            spec.lumbar.preset = volume::parseLumbarPreset(preset);
            spec.lumbar.bmi = bmi;
            spec.torso.lesionRadiusMm = lesionRadiusMm;
            volume::GridSpec grid;
            if (!(spacing >= 0.01 && spacing <= 100.0)) throw ValueError("spacing: must be within 0.01..100 mm");
            grid.spacing = Vec3d::Constant(spacing);
            if (field == "1.5")
                grid.field = volume::FieldStrength::T1_5;
            else if (field == "3")
                grid.field = volume::FieldStrength::T3;
            else
                throw ValueError("field: expected '1.5' or '3', got '" + field + "'");
            const volume::PhantomModel model = volume::phantomModel(spec, table);
            py::gil_scoped_release release;
            return std::make_shared<Volume>(volume::makePhantom(model, grid, table));
        },
        py::arg("kind"), py::kw_only(), py::arg("spacing") = 0.5, py::arg("preset") = "average",
        py::arg("bmi") = std::nullopt, py::arg("layers") = std::nullopt, py::arg("tilt_deg") = 0.0,
        py::arg("radius_mm") = 10.0, py::arg("lesion_radius_mm") = 8.0, py::arg("field") = "1.5",
        "A synthetic phantom, as `voxhap phantom` makes it: 'slab' (layers=[(tissue, mm), ...], tilt_deg), "
        "'sphere' (radius_mm), 'lumbar' (preset, bmi) or 'torso' (lesion_radius_mm); spacing [mm].");

    m.def(
        "tissues",
        [] {
            py::list out;
            for (const auto& t : volume::TissueTable::builtin().tissues()) out.append(tissueDict(t));
            return out;
        },
        "The built-in tissue table (data/tissues.json) in canonical units, one dict per tissue");
}

} // namespace voxhap::python
