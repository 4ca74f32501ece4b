// SPDX-License-Identifier: Apache-2.0
/// @file MrWeighting.h
/// @brief What an MR series is (T1 map, T1-weighted, PD, T2, FLAIR, diffusion,
/// field map, phase, ...), decided from its header fields, and the BIDS sidecar
/// that carries those fields beside NIfTI, NRRD and MetaImage files
/// (docs/reference.md, "MR weighting from the headers").
///
/// ## The MR weighting rule
///
/// Only a **T1 map** or a **T1-weighted** series fills the `t1` grid; every
/// other series, and every series the rule cannot decide, loads as an
/// `intensity` grid that is never called T1 (`--t1-weighted` overrides, and the
/// override is recorded). The weighting is never guessed from image statistics.
/// The rule reads ScanningSequence (0018,0020), SequenceVariant (0018,0021),
/// ScanOptions (0018,0022), the sequence name (0018,0024, or PulseSequenceName
/// (0018,9005) in enhanced files), ImageType (0008,0008), TR, TE, TI, flip
/// angle, a b-value when a header gives one and, last, SeriesDescription and
/// ProtocolName. The first stage that decides wins:
///
/// 1. **ImageType.** `T1 MAP` → T1 map. `P`, `PHASE` → phase (a field map's
///    phase difference when the sequence is a field map). `B0 MAP`, `FIELD MAP`,
///    `B1 MAP`, `FLIP ANGLE MAP` → field map. `DIFFUSION`, `ADC`, `FA`,
///    `TRACEW` → diffusion. `PERFUSION`, `ASL`, `CBF`, `CBV`, `MTT`, `TTP` →
///    perfusion. `FMRI` → functional. `SWI`, `MNIP`, `QSM` → susceptibility.
///    Any other `… MAP` (T2, T2*, R2*, PD, MTR) or `FAT`/`FF` → other
///    quantitative map. `MIP`, `SUB` → derived projection or subtraction.
///    Other derived images (reformats such as `MPR`) keep their weighting and
///    go on to the next stages.
/// 2. **Purpose**, from the sequence name, the b-value and description
///    keywords: a field-map sequence (Siemens `fm…`, a description saying
///    field map / B0 map / fmap / TOPUP) is a field map *whatever its TR, TE
///    and flip angle*; diffusion (Siemens `ep_b…`/`re_b…`, b-value > 0, DWI,
///    DTI, diff, …); perfusion (ASL, pCASL, perf, DSC, DCE); susceptibility
///    (Siemens `swi…`, GE SWAN, SWI, QSM); functional (BOLD, fMRI; GE `epiRT`);
///    angiography (TOF, MRA, angio); localizer or calibration scans (localizer,
///    scout, survey, 3-plane, calibration).
/// 3. **Contrast**, from the sequence type and TR, TE, TI and flip angle
///    (thresholds below, each with its source):
///    - *Inversion recovery* (IR in ScanningSequence or ScanOptions, or TI > 0):
///      TI ≥ 1500 ms → FLAIR; TI ≤ 300 ms → STIR (fat nulled, not T1); TI in
///      between → T1-weighted (MPRAGE, GE BRAVO/IR-FSPGR, T1-FLAIR), unless TE
///      is long (spin echo ≥ 80 ms, gradient echo ≥ 15 ms). Without a TI,
///      Philips T1-TFE is T1-weighted by its vendor name; otherwise undecided.
///    - *Echo planar* (not diffusion or perfusion): gradient-echo EPI (`epfid`,
///      GR, Philips FEEPI) with TE ≥ 15 ms → T2*-weighted; spin-echo EPI →
///      the spin-echo table.
///    - *Spin echo / turbo spin echo* (SE; Siemens se, tse, spc, h2d; GE fse,
///      frfse, ssfse, cube; Philips SE, TSE): TR ≤ 800 ms and TE ≤ 30 ms →
///      T1-weighted; TR ≥ 1500 ms and TE ≤ 30 ms → PD-weighted; TR ≥ 1500 ms
///      and TE ≥ 80 ms → T2-weighted; anything between is undecided.
///    - *Balanced or coherent steady state* (TRSS; Siemens tfi, fi, psif, ci,
///      de; GE FIESTA; Philips B-TFE/B-FFE, T2-FFE) → steady state (T2/T1
///      contrast), not T1.
///    - *Spoiled gradient echo* (SP in SequenceVariant; Siemens fl, tfl;
///      GE spgr, fspgr, efgre3d, bravo, lava; Philips T1-FFE, T1-TFE): TE ≥ 15 ms →
///      T2*-weighted; otherwise T1-weighted when the signal's T1 sensitivity
///      |∂ln S/∂ln T1| ≥ 0.6 for T1 = 900 ms, else PD-weighted. For the spoiled
///      steady state S = M0 sin α (1 − E1)/(1 − E1 cos α), E1 = exp(−TR/T1),
///      that sensitivity is (TR/T1)·E1·[1/(1 − E1) − cos α/(1 − E1 cos α)]: ≈ 0
///      for a small flip (PD), ≈ ½ at the Ernst angle, → 1 for 90° at TR ≪ T1.
///      In the short-TR limit it is r²/(1 + r²) with r = flip / Ernst angle,
///      so 0.6 means a flip ≥ 1.22 × the Ernst angle. Magnetization-prepared
///      spoiled sequences without a TI (MP) are not judged by the flip angle:
///      the preparation, not the flip, sets their contrast.
///    - A gradient echo of unknown spoiling with TE ≥ 15 ms → T2*-weighted.
/// 4. **Description**, only when nothing above decided: SeriesDescription and
///    ProtocolName keywords, matched on whole tokens (`T1` does not match
///    `T10`, `PD` does not match `UPDATE`): T1, T1w, MPRAGE, BRAVO, SPGR,
///    FSPGR, VIBE, LAVA, THRIVE, T1-FFE/TFE, T1-FLAIR → T1-weighted; T1 map →
///    T1 map; T2, HASTE, SSFSE → T2; T2* → T2*; PD → PD; FLAIR, dark fluid →
///    FLAIR; STIR → STIR. A description naming both T1 and another contrast
///    decides nothing. The reason then says that only the description decided.
/// 5. Otherwise **unknown**: an intensity grid, never T1.
///
/// ## Thresholds and their sources
///
/// T1 values are physics.md §5.1's; each constant below documents its value.
/// - STIR: TI ≤ 300 ms. Fat nulls at T1·ln 2 = 201 ms (1.5 T) and 265 ms (3 T);
///   300 ms adds a margin [chosen] and stays below GE BRAVO's TI ≈ 450 ms.
/// - FLAIR: TI ≥ 1500 ms. CSF (T1 ≈ 4200 ms) nulls at TI = T1·ln(2/(1 + e^(−TR/T1)))
///   (Bernstein, King & Zhou 2004, inversion recovery): ≈ 1540 ms at TR 4000 ms, ≈ 2000 ms
///   at TR 6000 ms; T1-weighted IR uses TI ≈ 400–1200 ms.
/// - Spin echo: short TR ≤ 800 ms, long TR ≥ 1500 ms, short TE ≤ 30 ms, long
///   TE ≥ 80 ms (IMAIOS e-MRI "Signal weighting": short TR ≈ the tissues' T1,
///   long TR > 1500 ms, short TE < 30 ms, long TE > 90 ms; 800 and 80 [chosen]
///   for 3 T, where muscle and white matter have T1 ≈ 900 ms).
/// - Gradient echo: TE ≥ 15 ms is T2*-weighted (teaching values: T1-weighted
///   GRE TE 2–10 ms, T2*-weighted 15–25 ms; TE/T2* of muscle is then 0.5–0.6).
/// - Spoiled gradient echo: T1 sensitivity ≥ 0.6 at T1 = 900 ms (the spoiled
///   steady-state signal and the Ernst angle, Bernstein et al. 2004, gradient echo;
///   0.6 [chosen] between the Ernst angle's 0.5 and 90° at TR 800 ms, 0.62).
/// - BIDS sidecars: times above 100 s (TR), 2 s (TE) or 10 s (TI) were
///   written in milliseconds and are refused [chosen].
#pragma once

#include "volume/VolumeMetadata.h"

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>

namespace voxhap::volume {

/// @name Thresholds of the MR weighting rule
/// @{

/// STIR versus T1-weighted inversion recovery: highest TI that still nulls fat [ms].
/// Fat nulls at TI = T1·ln 2 (TR ≫ T1): 290·0.693 = 201 ms at 1.5 T and
/// 382·0.693 = 265 ms at 3 T (physics.md §5.1, de Bazelaire 2004); clinical
/// STIR uses TI ≈ 150–250 ms. 300 ms leaves a margin above the 3 T null [chosen],
/// and stays below the shortest T1-weighted IR-prepared gradient echo
/// (GE BRAVO, TI ≈ 400–450 ms).
inline constexpr double kMrStirMaxTiMs = 300.0;

/// FLAIR versus T1-weighted inversion recovery: lowest TI of fluid suppression [ms].
/// After an inversion, Mz = M0·(1 − 2e^(−TI/T1) + e^(−TR/T1)) nulls at
/// TI = T1·ln(2 / (1 + e^(−TR/T1))) (Bernstein, King & Zhou, "Handbook of MRI
/// Pulse Sequences", 2004, the inversion-recovery section). For CSF (T1 4160–4280 ms,
/// physics.md §5.1) that is ≈ 1540 ms at TR 4000 ms and ≈ 2000 ms at TR 6000 ms.
/// T1-weighted IR (MPRAGE, T1-FLAIR) uses TI ≈ 400–1200 ms, so 1500 ms
/// separates the two.
inline constexpr double kMrFlairMinTiMs = 1500.0;

/// Spin echo: longest "short" TR of T1 weighting [ms]. Short TR means TR at or
/// below the tissues' T1 (IMAIOS e-MRI, "Signal weighting": short TR ≈ the
/// average T1, usually < 500 ms at 1.5 T). 800 ms [chosen] because T1 grows
/// with field: muscle and white matter have T1 ≈ 860–900 ms at 1.5–3 T
/// (physics.md §5.1). A 90° excitation at TR = 800 ms has T1 sensitivity
/// 0.62 ≥ kMrMinT1Sensitivity, so this and the gradient-echo rule agree.
inline constexpr double kMrSeShortTrMaxMs = 800.0;

/// Spin echo: shortest "long" TR of PD and T2 weighting [ms] (IMAIOS e-MRI,
/// "Signal weighting": long TR usually > 1500 ms).
inline constexpr double kMrSeLongTrMinMs = 1500.0;

/// Longest "short" TE [ms] (IMAIOS e-MRI, "Signal weighting": short TE usually < 30 ms).
inline constexpr double kMrShortTeMaxMs = 30.0;

/// Spin echo: shortest "long" TE of T2 weighting [ms]. IMAIOS gives > 90 ms,
/// other teaching material 80–120 ms for T2-weighted spin echo; 80 ms [chosen].
inline constexpr double kMrLongTeMinMs = 80.0;

/// Gradient echo: shortest TE of T2* weighting, and the bound T1 weighting
/// stays below [ms]. T1-weighted GRE uses TE ≈ 2–10 ms, T2*-weighted GRE
/// 15–25 ms and BOLD EPI 25–50 ms (radiographer teaching notes, e.g. the
/// ASMIRT exam material). Muscle T2* is ≈ 25–30 ms at 1.5 T, so at TE = 15 ms
/// the T2* sensitivity TE/T2* is 0.5–0.6: as large as the T1 sensitivity a
/// T1-weighted spoiled gradient echo must reach (kMrMinT1Sensitivity) [chosen].
inline constexpr double kMrT2StarMinTeMs = 15.0;

/// Reference T1 of the spoiled-gradient-echo test [ms]: paravertebral muscle,
/// 856 ms at 1.5 T and 898 ms at 3 T; white matter 876 ms at 3 T
/// (physics.md §5.1). The same value serves both field strengths: the Ernst
/// angle moves by ≈ 2 % between them.
inline constexpr double kMrReferenceT1Ms = 900.0;

/// Lowest T1 sensitivity |∂ln S/∂ln T1| of a T1-weighted spoiled gradient echo.
/// It is ≈ 0.5 at the Ernst angle, where T1 and proton density weigh equally,
/// and 0.62 for a 90° excitation at the spin-echo short-TR limit (800 ms);
/// 0.6 [chosen] calls a series T1-weighted once T1 dominates, i.e. a flip
/// ≥ 1.22 × the Ernst angle at short TR.
inline constexpr double kMrMinT1Sensitivity = 0.6;

/// @name Longest plausible BIDS times [s]
/// A sidecar time above its limit was written in milliseconds, not in BIDS's
/// seconds, and is refused rather than read 1000 times too long [chosen, with
/// a wide margin]: the longest TRs in use are ≈ 10–20 s, the longest TEs
/// ≈ 1 s (heavily T2-weighted MR cholangiography), the longest TIs ≈ 3–4 s
/// (double inversion recovery, FLAIR at 3 T).
/// @{
inline constexpr double kBidsMaxRepetitionTimeS = 100.0;
inline constexpr double kBidsMaxEchoTimeS = 2.0;
inline constexpr double kBidsMaxInversionTimeS = 10.0;
/// @}

/// @}

/// @brief The header fields the rule reads, from DICOM or a BIDS sidecar.
/// Empty strings and absent optionals mean "not given". Strings keep DICOM's
/// backslash between values; surrounding spaces are ignored.
struct MrSequenceFields {
    std::string scanningSequence; ///< (0018,0020), e.g. "GR\\IR", "SE", "EP", "IR"
    std::string sequenceVariant;  ///< (0018,0021), e.g. "SP\\MP", "SK\\SP"
    std::string scanOptions;      ///< (0018,0022), e.g. "IR", "IR_GEMS", "FS"
    /// (0018,0024), e.g. "*tfl3d1_ns", "fm2d2r", "*ep_b1000#1"; in enhanced
    /// files (0018,9005) PulseSequenceName, e.g. Philips "T1TFE"
    std::string sequenceName;
    std::string imageType;                  ///< (0008,0008), backslash-separated, e.g. "ORIGINAL\\PRIMARY\\M\\ND"
    std::string description;                ///< (0008,103E) SeriesDescription
    std::string protocolName;               ///< (0018,1030) ProtocolName
    std::optional<double> repetitionTimeMs; ///< (0018,0080) TR [ms]
    std::optional<double> echoTimeMs;       ///< (0018,0081) TE [ms]
    std::optional<double> inversionTimeMs;  ///< (0018,0082) TI [ms]
    std::optional<double> flipAngleDeg;     ///< (0018,1314) [deg]
    std::optional<double> bValue;           ///< diffusion b-value [s/mm²], when a header gives it
    /// Where the fields came from, for messages: "DICOM headers", "BIDS sidecar x.json".
    std::string source;
};

/// @brief The rule's verdict (MrWeightingKind and its names are in
/// volume/VolumeMetadata.h, where the volume keeps it).
struct MrWeighting {
    MrWeightingKind kind = MrWeightingKind::Unknown;
    std::string name; ///< mrWeightingName(kind), for metadata and `voxhap info`
    /// One line: which fields decided and why, e.g. "ScanningSequence GR\IR with
    /// TI 850 ms: inversion-prepared gradient echo (MPRAGE type) ...".
    std::string reason;

    /// @brief True only for T1 maps and T1-weighted series: the ones that fill `t1`.
    bool fillsT1() const { return kind == MrWeightingKind::T1Map || kind == MrWeightingKind::T1Weighted; }
};

/// @brief Apply the MR weighting rule (this file's header) to one series' fields.
/// Never throws; a series nothing decides is MrWeightingKind::Unknown.
MrWeighting classifyMrWeighting(const MrSequenceFields& f);

/// @brief T1 sensitivity |∂ln S/∂ln T1| of the spoiled gradient-echo steady
/// state S = M0 sin α (1 − E1)/(1 − E1 cos α), E1 = exp(−TR/T1).
/// @param trMs    repetition time [ms], > 0
/// @param flipDeg flip angle α [deg]
/// @param t1Ms    tissue T1 [ms], > 0
/// @return 0 (no T1 weighting) to ≈ 1 (signal ∝ 1/T1); ≈ 0.5 at the Ernst angle
double spoiledGreT1Sensitivity(double trMs, double flipDeg, double t1Ms);

/// @brief The sidecar dcm2niix writes beside an image: the same name with
/// `.json` (x.nii.gz, x.nii, x.nrrd, x.nhdr, x.mha, x.mhd, x.hdr → x.json).
std::filesystem::path bidsSidecarPath(const std::filesystem::path& image);

/// @brief What a BIDS sidecar says about its image.
struct BidsSidecar {
    std::filesystem::path file;           ///< the sidecar read
    MrSequenceFields fields;              ///< times converted to ms; source names the file
    std::string modality;                 ///< "Modality", e.g. "MR"; empty when absent
    std::optional<double> fieldStrengthT; ///< "MagneticFieldStrength" [T]
};

/// @brief Read a BIDS sidecar (JSON). BIDS times are in seconds and come back
/// in ms: RepetitionTime, EchoTime, InversionTime (a number, or an array of
/// numbers whose first is taken). FlipAngle [deg] and MagneticFieldStrength [T]
/// are numbers. ScanningSequence, SequenceVariant, ScanOptions and ImageType
/// are strings or arrays of strings (joined with a backslash); SequenceName
/// (else PulseSequenceName), SeriesDescription, ProtocolName and Modality are
/// strings. Other keys are ignored; absent or null keys stay empty.
/// @throw IoError naming the file (and the field) when it cannot be read, is
///        not a JSON object, or a field has the wrong type, is negative or
///        non-finite, or is a time above its kBidsMax…S limit; one line.
BidsSidecar readBidsSidecar(const std::filesystem::path& json);

/// @brief The sidecar beside @p image (bidsSidecarPath), read; std::nullopt
/// when there is none.
/// @throw IoError as readBidsSidecar when the sidecar exists but is malformed
std::optional<BidsSidecar> readBidsSidecarBeside(const std::filesystem::path& image);

} // namespace voxhap::volume
