// SPDX-License-Identifier: Apache-2.0
/// @file Bindings.h
/// @brief What the parts of the `voxhap` Python module share: the registration
/// function of each part, and conversions between voxhap's types and Python's.
#pragma once

#include "volume/Volume.h"

#include <nlohmann/json_fwd.hpp>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <memory>
#include <string>

namespace voxhap::python {

namespace py = pybind11;

/// @brief Volumes, grids as numpy arrays, files, phantoms, the tissue table.
void bindVolume(py::module_& m);
/// @brief Material field, shaft integration, scenes, one force-model step, simulate.
void bindHaptic(py::module_& m);
/// @brief Segmentation and path planning.
void bindPlanning(py::module_& m);
/// @brief CT and MR fusion (built with the registration library).
void bindFusion(py::module_& m);

/// @brief A JSON value as the Python value json.loads gives (dict, list, float, ...).
py::object toPython(const nlohmann::json& j);

/// @brief The dense array of a FloatGrid or Int32Grid over @p v's index box,
/// shape (ni, nj, nk), inactive voxels holding the grid's background.
/// @throw ValueError for another grid type
py::array gridToArray(const volume::Volume& v, const openvdb::GridBase& grid);

} // namespace voxhap::python
