// SPDX-License-Identifier: Apache-2.0
/// @file VolumeMetadata.h
/// @brief What a volume's metadata say, as typed facts that code reads, and
/// free text kept only for display.
///
/// Every fact another library reads (the field strength that picks the T1
/// damping law, the MR weighting, the modality and where each came from, the
/// series and volume chosen, a phantom's layers and landmarks) is a typed
/// member with a stable name: the name is its key in `.vdb` files
/// (`voxhap.<name>`), in NRRD headers (`voxhap_<name>:=`), in `voxhap info
/// --json` and in Python's `metadata` dict (docs/reference.md "Volume
/// metadata"). `extra` holds the rest, text for people: nothing decides on it.
#pragma once

#include "core/Math.h"
#include "volume/FusionRecord.h"

#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace voxhap::volume {

/// @brief MR field strength: T1 depends on it (physics.md §5.1), and so does
/// the T1 damping law (§5.4). The tissue table and the law are known at these
/// two only.
enum class FieldStrength {
    T1_5,
    T3
};

/// @brief "1.5T" or "3T".
std::string_view fieldStrengthName(FieldStrength f);
/// @brief The inverse of fieldStrengthName, or nothing.
std::optional<FieldStrength> parseFieldStrength(std::string_view name);

/// How far a scanner's nominal field [T] may lie from 1.5 T or 3 T and still
/// take that field's T1 values and law: vendors write e.g. 1.494 or 2.89 for
/// their 1.5 T and 3 T systems; 1.0 T, 0.5 T or 7 T systems lie well outside.
inline constexpr double kFieldStrengthToleranceT = 0.25;

/// @brief The field strength a MagneticFieldStrength value [T] stands for:
/// 1.5 T or 3 T within kFieldStrengthToleranceT, else nothing (physics.md §5.4
/// "Field strength": such a scan gets no T1 law rather than a wrong one).
std::optional<FieldStrength> fieldStrengthOfTesla(double tesla);

/// @brief Where a fact came from.
enum class FactSource {
    Unknown,   ///< not recorded: a foreign file, or one whose writer did not say
    Header,    ///< the file's own header: a DICOM element, a voxhap NRRD key
    Sidecar,   ///< a BIDS JSON sidecar beside the file
    User,      ///< declared by the user (a command-line option)
    Data,      ///< inferred from the image values
    Assumed,   ///< a default, because nothing said
    Generator, ///< the phantom generator's spec
};

/// @brief "unknown", "header", "sidecar", "user", "data", "assumed" or "generator".
std::string_view factSourceName(FactSource s);
/// @brief The inverse of factSourceName, or nothing.
std::optional<FactSource> parseFactSource(std::string_view name);

/// @brief What an MR series is. Only T1Map and T1Weighted fill the `t1` grid
/// (the rule that decides is in volume/mr/MrWeighting.h).
enum class MrWeightingKind {
    T1Map,          ///< quantitative T1 [ms]
    T1Weighted,     ///< T1-weighted signal (normalised per scan, T1Normalisation.h)
    PdWeighted,     ///< proton-density-weighted
    T2Weighted,     ///< T2-weighted
    T2StarWeighted, ///< T2*-weighted (long-TE gradient echo)
    Flair,          ///< long-TI inversion recovery (fluid suppressed)
    Stir,           ///< short-TI inversion recovery (fat suppressed)
    SteadyState,    ///< balanced or coherent steady state (T2/T1 contrast)
    Diffusion,      ///< diffusion-weighted, or a map derived from it (ADC, FA, trace)
    FieldMap,       ///< B0 or B1 field map, magnitude or phase difference
    Phase,          ///< phase image
    Perfusion,      ///< ASL, DSC or DCE series and their maps
    Functional,     ///< BOLD fMRI
    Susceptibility, ///< SWI, SWAN, QSM
    Angiography,    ///< time of flight or contrast-enhanced MRA
    Localizer,      ///< localizer, scout or calibration scan
    OtherMap,       ///< quantitative map other than T1 (T2, T2*, PD, MTR, fat fraction)
    Derived,        ///< projection (MIP, minIP) or subtraction image
    Unknown,        ///< nothing decides: an intensity grid, never T1
};

/// @brief The display name of @p k, as saved under "mr_weighting":
/// "T1 map", "T1-weighted", "PD-weighted", "T2-weighted", "T2*-weighted",
/// "FLAIR", "STIR", "steady state", "diffusion", "field map", "phase",
/// "perfusion", "functional", "susceptibility", "angiography", "localizer",
/// "quantitative map", "derived", "unknown".
std::string_view mrWeightingName(MrWeightingKind k);
/// @brief The inverse of mrWeightingName, or nothing.
std::optional<MrWeightingKind> parseMrWeighting(std::string_view name);

/// @brief What the values of a `t1` grid are.
enum class T1Kind {
    Map,                ///< a T1 map: T1 [ms] per voxel, measured (or a phantom's table values)
    NormalisedWeighted, ///< a T1-weighted signal normalised per scan (physics.md §5.1)
};

/// @brief "T1 map" or "T1-weighted, normalised per scan".
std::string_view t1KindName(T1Kind k);
/// @brief The inverse of t1KindName, or nothing.
std::optional<T1Kind> parseT1Kind(std::string_view name);

/// @brief The volume chosen from a 4D series (DICOM echoes, time points, b-values).
struct VolumeChoice {
    int index = 1;     ///< 1-based
    int count = 1;     ///< volumes in the series
    std::string label; ///< what tells it apart, e.g. "echo 2 (TE 7.38 ms)", "b=1000"

    bool operator==(const VolumeChoice&) const = default;
};

/// @brief "2 of 13 (b=1000)".
std::string volumeChoiceText(const VolumeChoice& c);

/// @brief One tissue interval along a straight path.
struct LayerSpan {
    int tissue = 0;     ///< tissue id
    std::string name;   ///< tissue name
    double startMm = 0; ///< distance from the path's start [mm]
    double endMm = 0;   ///< distance from the path's start [mm]

    bool operator==(const LayerSpan&) const = default;
};

/// @brief A phantom's layer table along its reference path, from the analytic
/// model (not the voxels).
struct PhantomLayers {
    Vec3d entry{0, 0, 0};
    Vec3d direction{0, -1, 0};
    std::vector<LayerSpan> layers;

    bool operator==(const PhantomLayers& o) const
    {
        return entry == o.entry && direction == o.direction && layers == o.layers;
    }
};

/// @brief Descriptive metadata saved with the volume. No patient identity.
struct VolumeMetadata {
    /// "CT", "MR", "phantom", another DICOM Modality (0008,0060) code, or "unknown".
    std::string modality;
    FactSource modalitySource = FactSource::Unknown;
    /// One line: which field or rule decided the modality, for display.
    std::string modalityReason;
    std::string source;      ///< file or generator that made the volume
    std::string description; ///< free text, patient-free
    std::string huUnits = "HU";
    std::string t1Units = "ms";                     ///< always "ms": the t1 grid holds T1 only
    std::string intensityUnits = "arbitrary units"; ///< of the intensity grid
    /// MR only: what the series is, as decided from its headers (MrWeighting.h);
    /// MrWeightingKind::Unknown when nothing says; empty for CT and phantoms.
    std::optional<MrWeightingKind> mrWeighting;
    /// What the `t1` grid holds; empty without one, or when no loader said.
    std::optional<T1Kind> t1Kind;
    /// The field strength whose T1 values and damping law apply; empty when
    /// nothing is known, or when the scanner's field is neither 1.5 T nor 3 T
    /// (then fieldStrengthTesla holds it).
    std::optional<FieldStrength> fieldStrength;
    FactSource fieldStrengthSource = FactSource::Unknown;
    /// The nominal field the header or sidecar gave [T], as written.
    std::optional<double> fieldStrengthTesla;
    /// MR only: the widest body section measured for the trunk rule [mm]
    /// (volume/mr/BodyWidth.h).
    std::optional<double> bodyWidthMm;
    /// DICOM only: the SeriesInstanceUID (0020,000E) of the series loaded.
    std::string seriesUid;
    /// The volume chosen from a 4D series; empty for a 3D series.
    std::optional<VolumeChoice> volumeChoice;
    /// A phantom's layer table along its reference path.
    std::optional<PhantomLayers> phantomLayers;
    /// A phantom's named points [mm, LPS], e.g. "lesion", "entry", "aorta".
    std::map<std::string, Vec3d> landmarks;
    /// Display only: further notes (saved as "voxhap.extra.<key>"), e.g. how
    /// the MR background was removed. Code never decides on them.
    std::map<std::string, std::string> extra;
    /// A fused CT and MR (fusion/PatientFusion.h): the registration and the channels' sources.
    std::optional<FusionRecord> fusion;

    bool operator==(const VolumeMetadata&) const = default;
};

/// @brief Record an MR's field strength: the MagneticFieldStrength @p tesla
/// its header or sidecar gave (@p from), or, without one, @p assumed as
/// assumed. A value neither 1.5 T nor 3 T (fieldStrengthOfTesla) is recorded
/// in fieldStrengthTesla alone, and no law is chosen for it.
void recordFieldStrength(VolumeMetadata& md, std::optional<double> tesla, FactSource from, FieldStrength assumed);

/// @name The typed facts as text, under their stable names.
/// The one codec for files (.vdb, NRRD), reports and Python.
/// @{
/// @brief The facts that are set, in a fixed order: "modality",
/// "modality_source", "modality_reason", "mr_weighting", "t1_kind",
/// "field_strength", "field_strength_source", "field_strength_tesla",
/// "body_width_mm", "series_uid", "volume", "volume_count", "volume_label",
/// "layers" (JSON), "landmarks" (JSON), "fusion" (JSON, FusionRecord.h). Source, description and units are not
/// among them: each file format keeps its own keys for those.
std::vector<std::pair<std::string, std::string>> metadataFacts(const VolumeMetadata& md);
/// @brief Set the fact @p name from its text.
/// @return false if @p name is not a fact's name (the caller may keep it as extra)
/// @throw ValueError naming @p where and the fact if the text is not a valid value
bool setMetadataFact(VolumeMetadata& md, std::string_view name, const std::string& text, const std::string& where);
/// @brief Read the facts a file wrote before they were typed, from its extras
/// ("field_strength", "t1_kind", "modality_source", "layers", ...), into the
/// typed members, and drop those extras. Facts already set stay.
/// @throw ValueError naming @p where if an old value is malformed
void upgradeLegacyExtras(VolumeMetadata& md, const std::string& where);
/// @}

} // namespace voxhap::volume
