// SPDX-License-Identifier: Apache-2.0
/// @file Phantoms.h
/// @brief Synthetic test volumes with known anatomy (physics.md §7, §2.3, §3.3, §1.1).
///
/// All phantoms share one frame: world LPS in mm, the skin surface at y = 0
/// on the reference path, the body at y < 0 (a prone patient seen from the
/// back: the needle advances along -y, anterior). Each fills hu, t1 and label
/// from the tissue table, and records in its metadata the layer table along
/// its reference path ("layers") and named points ("landmarks").
#pragma once

#include "phantoms/Rasterize.h"

#include <optional>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief One layer of a slab stack.
struct SlabLayer {
    std::string tissue;     ///< tissue name from the table
    double thicknessMm = 0; ///< [mm]
};

/// @brief Layered slab stack (physics.md §7 R1).
struct SlabParams {
    std::vector<SlabLayer> layers{{"skin", 2.0}, {"fat", 8.0}, {"muscle", 20.0}};
    double tiltDeg = 0.0;      ///< layer normal tilted from +y about the world x axis [deg]
    double halfWidthMm = 20.0; ///< lateral half extent of the block in x and z [mm]
    double airMarginMm = 5.0;  ///< air above the surface [mm]
    GridSpec grid;
};

/// @brief A sphere of one tissue in a slab of another (physics.md §7 R5).
struct SphereParams {
    std::string slabTissue = "fat";
    std::string sphereTissue = "muscle";
    double slabThicknessMm = 40.0; ///< [mm]; the sphere is centred at half this depth
    double radiusMm = 10.0;        ///< [mm]
    double halfWidthMm = 25.0;     ///< lateral half extent [mm]
    double airMarginMm = 5.0;      ///< [mm]
    GridSpec grid;
};

/// @brief Patient types of the epidural simulator (physics.md §2.3, [S19] Table I).
enum class LumbarPreset {
    Average,
    Overweight,
    Calcified
};

/// @brief Parse "average", "overweight" or "calcified". @throw ValueError
LumbarPreset parseLumbarPreset(const std::string& name);
std::string lumbarPresetName(LumbarPreset p);

/// @brief Lumbar epidural phantom: two vertebrae and the midline layers.
struct LumbarParams {
    LumbarPreset preset = LumbarPreset::Average;
    /// Body-mass index: when set, the layers above the epidural space are scaled so
    /// that skin-to-epidural distance SED = 2.52 + 0.11·BMI cm (physics.md §3.3).
    std::optional<double> bmi;
    GridSpec grid;
};

/// @brief Midline layer thicknesses of the lumbar phantom [mm], posterior to anterior.
struct LumbarLayout {
    double skin = 0, fat = 0, supraspinous = 0, interspinous = 0, flavum = 0;
    double epidural = 0, dura = 0, csf = 0;
    double scale = 1.0; ///< BMI scale factor applied above the epidural space (1 without BMI)
    /// Skin-to-epidural-space distance [mm].
    double sed() const { return skin + fat + supraspinous + interspinous + flavum; }
};

/// @brief The midline thicknesses for a preset and optional BMI, from the table.
/// Derma (skin + fat) and epidural length per [S19] Table I; the other layers
/// from the table's default thicknesses. @throw ValueError on an implausible BMI.
LumbarLayout lumbarLayout(const LumbarParams& p, const TissueTable& table);

/// @brief Spine-biopsy torso (physics.md §1.1): skin, fat, muscle, a vertebral
/// body with a lesion, lung bases, kidneys and aorta.
struct TorsoParams {
    double lesionRadiusMm = 8.0; ///< [mm]
    GridSpec grid;
};

/// @brief An analytic phantom: its classifier, extent and reference path.
struct PhantomModel {
    std::string kind;        ///< "slab", "sphere", "lumbar" or "torso"
    std::string description; ///< one line, with the parameters
    Classifier classify;
    WorldBox bounds;
    Vec3d pathEntry{0, 0, 0};                             ///< reference path start (on the skin) [mm]
    Vec3d pathTarget{0, 0, 0};                            ///< reference path end [mm]
    std::vector<std::pair<std::string, Vec3d>> landmarks; ///< named points [mm]
};

PhantomModel slabModel(const SlabParams& p, const TissueTable& table);
PhantomModel sphereModel(const SphereParams& p, const TissueTable& table);
PhantomModel lumbarModel(const LumbarParams& p, const TissueTable& table);
PhantomModel torsoModel(const TorsoParams& p, const TissueTable& table);

/// @brief A phantom by name with its parameters, as `voxhap phantom`, scenes and
/// regression suites describe one; only the parameters of its kind are read.
struct PhantomSpec {
    std::string kind; ///< "slab", "sphere", "lumbar" or "torso"
    SlabParams slab;
    SphereParams sphere;
    LumbarParams lumbar;
    TorsoParams torso;
};

/// @brief The model of @p spec's kind. @throw ValueError naming an unknown kind
PhantomModel phantomModel(const PhantomSpec& spec, const TissueTable& table);

/// @brief Rasterise a model and record its layers and landmarks in the metadata.
Volume makePhantom(const PhantomModel& model, const GridSpec& grid, const TissueTable& table);

/// @brief The layer table of a phantom (VolumeMetadata::phantomLayers), or empty if none.
std::optional<PhantomLayers> phantomLayers(const Volume& v);

/// @brief The named point @p name of a phantom (VolumeMetadata::landmarks), or
/// nothing if the volume has no such landmark.
std::optional<Vec3d> phantomLandmark(const Volume& v, const std::string& name);

} // namespace voxhap::volume
