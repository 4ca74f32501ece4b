// SPDX-License-Identifier: Apache-2.0
/// @file RenderBench.h
/// @brief The rendering figure of benchmarks.md: seconds per four-view
/// snapshot of the viewer (axial, sagittal, coronal in software, 3D by VTK),
/// first frame (3D pipeline built, shaders compiled) and steady frame (every
/// pane redrawn) and the frame after a streamed needle pose, the 3D pane in the viewer's default colour mode (CPU ray
/// caster, VolumeView3d's Auto), on the real CT and on a 256³ phantom.
///
/// And the interactive 3D pane: a scripted orbit of a 512 ×
/// 375 3D view (azimuth steps of 360°/N, OrbitCamera) drawn at
/// RenderQuality::Moving by each candidate moving path, frames/s median and
/// 10th percentile; the full-quality frame at the same camera; and the time
/// from the end of the orbit (the drag released) to the full-quality frame.
/// Every ratio is against the full-quality frame of the same run.
#pragma once

#include "core/Progress.h"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

namespace voxhap::bench {

struct RenderBenchOptions {
    std::string ct;                          ///< a DICOM folder (or any volume); empty: phantom only
    int phantomSide = 256;                   ///< voxels per side of the torso phantom
    int firstFrames = 2;                     ///< fresh viewers, each timed on its first frame
    int steadyFrames = 5;                    ///< redraws of one viewer, after its first frame
    int width = 1024, height = 1048;         ///< window [px] (the viewer's default)
    bool fourView = true;                    ///< the four-view frames (false: the orbit only)
    int orbitFrames = 36;                    ///< moving frames of the orbit per candidate (0: no orbit)
    int fullFrames = 3;                      ///< full-quality frames per candidate, for the median
    int orbitWidth = 512, orbitHeight = 375; ///< the 3D view of the orbit [px]
};

/// @brief One moving path measured on one volume's orbit.
/// @brief One ray step of the full-quality frame, against the viewer's one voxel.
struct FullStep {
    double stepVoxels = 1.0;   ///< View3dStyle::sampleVoxels
    double fullS = 0;          ///< median full-quality frame at the home camera [s]
    double cpuFullS = 0;       ///< process CPU seconds per frame, median
    double greyVsOneVoxel = 0; ///< mean |grey difference| against the one-voxel frame [0..255]
};

struct OrbitCase {
    std::string volume, path;    ///< e.g. "real CT", "subsample x3"
    bool chosen = false;         ///< the viewer's default moving path
    double firstFullS = 0;       ///< the view's first full-quality frame (tables built)
    double firstMovingS = 0;     ///< its first moving frame (the moving path's tables built)
    double fullS = 0;            ///< median full-quality frame at the home camera [s]
    double fpsMedian = 0;        ///< moving frames per second over the orbit, median
    double fpsP10 = 0;           ///< and 10th percentile (the slow frames)
    double stopToFullS = 0;      ///< drag released at the orbit's end → full-quality frame on screen [s]
    double fullOverMoving = 0;   ///< median full frame over median moving frame, this run
    double movingVsFullGrey = 0; ///< mean |grey difference| of the moving and full frames at one camera [0..255]
    double cpuMovingS = 0;       ///< process CPU seconds per moving frame, median (all threads): the load-free cost
    double cpuFullS = 0;         ///< process CPU seconds per full-quality frame, median
    int frames = 0;
    std::size_t trianglesFull = 0;   ///< critical-surface triangles of the full frame (0: no labels)
    std::size_t trianglesMoving = 0; ///< and of the moving frame (from the sampled label map)
    /// The chosen path's case only: the full frame at longer ray steps, the
    /// candidates for full quality within 1.5 s of stopping.
    std::vector<FullStep> fullSteps;
    double viewerVsOneVoxelGrey = 0; ///< the viewer's own full frame against one-voxel steps, home camera
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
    std::vector<OrbitCase> orbits;
    int orbitWidth = 0, orbitHeight = 0;
};

/// @throw IoError, ValueError if the CT cannot be read; IoError if no display can be had
RenderReport runRenderBench(const RenderBenchOptions& o, const Progress& progress = {});
void printRenderReport(std::ostream& os, const RenderReport& r);
nlohmann::json renderReportJson(const RenderReport& r);

} // namespace voxhap::bench
