// SPDX-License-Identifier: Apache-2.0
/// @file RenderBench.h
/// @brief The rendering figure of benchmarks.md: seconds per four-view
/// snapshot of the viewer (axial, sagittal, coronal in software, 3D by VTK),
/// first frame (3D pipeline built, shaders compiled) and steady frame (every
/// pane redrawn) and the frame after a streamed needle pose, the 3D pane in the viewer's default colour mode (CPU ray
/// caster, VolumeView3d's Auto), on the real CT and on a 256³ phantom.
#pragma once

#include "core/Progress.h"

#include <nlohmann/json.hpp>

#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace voxhap::bench {

struct RenderBenchOptions {
    std::string ct;                  ///< a DICOM folder (or any volume); empty: phantom only
    int phantomSide = 256;           ///< voxels per side of the torso phantom
    int firstFrames = 2;             ///< fresh viewers, each timed on its first frame
    int steadyFrames = 5;            ///< redraws of one viewer, after its first frame
    int width = 1024, height = 1048; ///< window [px] (the viewer's default)
};

/// @brief Mean and sample standard deviation [s].
struct Seconds {
    double mean = 0, sd = 0;
    int n = 0;
};

struct RenderCase {
    std::string name, dims;      ///< e.g. "real CT", "512 x 512 x 134"
    double loadS = 0;            ///< reading the volume (not part of a frame)
    Seconds setup;               ///< the viewer: volume copied for VTK, frames laid out
    Seconds first;               ///< the first four-view frame of a fresh viewer
    Seconds steady;              ///< a later four-view frame, all panes redrawn
    Seconds slices;              ///< after a new needle pose: slices and overlays redrawn, the 3D picture cached
    double steadyOverSlices = 0; ///< steady over needle frame, per round in this run: what the volume rendering costs
    long differingPixels = 0;    ///< steady frame against first frame: 0 if rendering is deterministic
};

struct RenderReport {
    std::string machine, display;
    std::vector<RenderCase> cases;
};

/// @throw IoError, ValueError if the CT cannot be read; IoError if no display can be had
RenderReport runRenderBench(const RenderBenchOptions& o, const Progress& progress = {});
void printRenderReport(std::ostream& os, const RenderReport& r);
nlohmann::json renderReportJson(const RenderReport& r);

} // namespace voxhap::bench
