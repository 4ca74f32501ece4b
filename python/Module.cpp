// SPDX-License-Identifier: Apache-2.0
/// @file Module.cpp
/// @brief The `voxhap` Python module: its docstring, version, the mapping of
/// voxhap's exceptions to Python's, and the parts (docs/reference.md "Python").

#include "python/Bindings.h"
#include "python/HapticBindings.h"

#include "core/Errors.h"
#include "core/Version.h"
#include "volume/Grids.h"
#ifdef VOXHAP_PYTHON_WITH_IGTL
#include "haptic/igtl/IgtlDevice.h"
#endif

#include <nlohmann/json.hpp>

namespace voxhap::python {

py::object toPython(const nlohmann::json& j)
{
    // Through the text: nlohmann writes infinities and NaN as null, which is what
    // the command line's --json shows too.
    return py::module_::import("json").attr("loads")(j.dump());
}

} // namespace voxhap::python

PYBIND11_MODULE(_voxhap, m)
{
    namespace py = pybind11;
    using namespace voxhap;
    m.doc() = "voxhap: needle-insertion forces from patient volumes. World space is patient LPS in mm, "
              "forces in N, speeds in mm/s; grids are numpy arrays indexed [i, j, k] with a 4x4 "
              "index-to-world transform.";
    m.attr("__version__") = std::string(kVersion);
    volume::initializeOpenVdb();

    // Bad input raises what a Python user expects: a file problem OSError, a bad
    // value ValueError; the message is the command line's one line (file and field).
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const IoError& e) {
            PyErr_SetString(PyExc_OSError, e.what());
        } catch (const ValueError& e) {
            PyErr_SetString(PyExc_ValueError, e.what());
        }
    });

    python::bindVolume(m);
    python::bindHaptic(m);
    python::bindServo(m);
    python::bindPlanning(m);
#ifdef VOXHAP_PYTHON_WITH_FUSION
    python::bindFusion(m);
#endif
#ifdef VOXHAP_PYTHON_WITH_IGTL
    // Device kinds of the libraries this module links, by their explicit call (DeviceSpec.h says why).
    haptic::registerIgtlDevice();
#endif
}
