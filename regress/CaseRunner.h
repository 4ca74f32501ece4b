// SPDX-License-Identifier: Apache-2.0
/// @file CaseRunner.h
/// @brief Runs the cases of a regression suite: builds each distinct volume once
/// per run (shared by the cases that use it), sets up the scene with the case's
/// strategy, drives the scripted insertion (haptic::runInsertion, as `voxhap
/// simulate` does) and records the force profile, the events and the
/// fingerprint of every input that shaped them.
#pragma once

#include "regress/Suite.h"

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace voxhap::regress {

/// @brief One stored point of a force–depth profile.
struct Sample {
    double depthMm = 0;   ///< tip depth along the path [mm]
    double modelN = 0;    ///< the model's axial resistance [N], + pushes out
    double renderedN = 0; ///< |F| sent to the device [N]
    double plungerN = 0;  ///< the loss-of-resistance syringe's plunger force [N] (§2.3), 0 without one
};

struct EventRecord {
    std::string event; ///< haptic::eventName
    double depthMm = 0;
};

/// @brief The extremes of every tick a sample stands for: those after the
/// previous sample, up to and including its own. A change the trainee feels
/// between two samples (a transient, a one-tick spike) moves them.
struct Envelope {
    double modelMin = 0, modelMax = 0;       ///< [N]
    double renderedMin = 0, renderedMax = 0; ///< [N]
    double plungerMin = 0, plungerMax = 0;   ///< [N]
};

/// @brief What a case produced (or what its baseline recorded).
struct Profile {
    std::vector<Sample> samples;    ///< every sample_mm of travel, and the last tick
    std::vector<Envelope> envelope; ///< one per sample (empty in a baseline written before it existed)
    std::vector<EventRecord> events;
    double peakModelN = 0, peakRenderedN = 0;
    std::string digest; ///< FNV-1a of every tick's depth and forces, bit for bit (hex)
};

/// @brief One recorded input: a number with its unit, or a text.
struct InputValue {
    std::string text; ///< the value as text (numbers too, shortest round trip)
    std::optional<double> number;
    std::string unit;
    bool operator==(const InputValue& o) const { return text == o.text && unit == o.unit; }
};
/// @brief The fingerprint: "skin.cutting_force" → 2.0 N, "scene.terms.damping.cap_N" → 6, ...
using Inputs = std::map<std::string, InputValue>;

/// @brief A layer along the path, for the explanation and the plot.
struct Band {
    std::string name;
    double startMm = 0, endMm = 0;
};

/// @brief An event a closed form places: its kind (haptic::eventName) and depth.
struct ExpectedEvent {
    std::string event;
    double depthMm = 0;
    double toleranceMm = 0; ///< the rule's own: the tick grid decides where it lands
};

/// @brief The closed form of physics.md §7 a case is checked against, per sample.
struct ClosedForm {
    std::string id;                 ///< "R1" … "R5"
    std::string rule;               ///< e.g. "physics.md §7 R1 (layered damping slab)"
    std::vector<double> modelN;     ///< the closed form at each sample's depth [N]
    std::vector<double> toleranceN; ///< allowed |ΔF| at each sample [N], from the rule's bound
    /// Events the rule places (R4: each pop), compared with the run's events of
    /// that kind shallower than @ref eventsUpToMm, in order.
    std::vector<ExpectedEvent> events;
    double eventsUpToMm = 0;
};

struct CaseRun {
    Profile profile;
    Inputs inputs;
    std::vector<Band> layers;
    /// A bending needle's tip off the straight line at the last tick [mm] (physics.md §9.6)
    std::optional<double> tipDeviationMm;
    double elapsedS = 0; ///< the case's own time (its share of the volume build not included)
};

/// @brief Options that apply to every case of a run.
struct RunOptions {
    std::string tissues;             ///< a tissue table used instead of every case's (--tissues)
    std::filesystem::path scenesDir; ///< scene NAME resolves to DIR/NAME.json when that exists (--scenes)
    int threads = 0;                 ///< 0: all cores
};

/// @brief Everything a run needs, prepared and checked before any case runs.
/// @throw ValueError "suite: cases.NAME.field: why" for an unknown scene, an
///        unreadable tissue table or script, an unknown tissue
class Runner {
public:
    Runner(const Suite& suite, std::vector<std::size_t> selected, const RunOptions& options);
    ~Runner();
    Runner(const Runner&) = delete;
    Runner& operator=(const Runner&) = delete;

    /// @brief Run the selected cases (in parallel; each case is single-threaded,
    /// so results do not depend on the thread count). Index i of the result is
    /// selected[i]. @throw ValueError naming the case when a case cannot be set up
    std::vector<CaseRun> run();
    /// @brief Seconds spent building the shared volumes.
    double volumeSeconds() const { return mVolumeSeconds; }
    std::size_t volumeCount() const;

private:
    CaseRun runOne(std::size_t k) const;
    struct Impl;
    const Suite& mSuite;
    std::vector<std::size_t> mSelected;
    RunOptions mOptions;
    std::unique_ptr<Impl> mImpl;
    double mVolumeSeconds = 0;
};

/// @brief A case's closed form, or why physics.md §7 has none for it.
struct ClosedFormCheck {
    ClosedFormCheck(ClosedForm f) : form(std::move(f)) { } // NOLINT: a rule that applies converts
    static ClosedFormCheck none(std::string why)
    {
        ClosedFormCheck c;
        c.why = std::move(why);
        return c;
    }
    std::optional<ClosedForm> form;
    std::string why; ///< without a form: the first precondition that fails ("term karnopp")
    explicit operator bool() const { return form.has_value(); }
    const ClosedForm* operator->() const { return &*form; }
    const ClosedForm& operator*() const { return *form; }
    /// @brief What `voxhap regress` prints: "closed form: R1" or "no closed form: <why>".
    std::string line() const;

private:
    ClosedFormCheck() = default;
};

/// @brief The closed form for a case, if physics.md §7 has one for it (the
/// damping slab R1, tilted or not, and the sphere in a slab R5, under a model
/// whose only axial term is voxel damping; the [LP] stack R2 and the Conci
/// profile R3 for their scenes' fixed tables; the Sénac nested boxes R4 on the
/// lumbar phantom's midline), evaluated at @p samples with the
/// tissue and scene values in @p recorded (the baseline's record, so that an
/// edited value fails here too) — missing keys fall back to @p current. Each
/// rule is computed from physics.md in regress's own code (R1 and R5 take β
/// from the recorded tissue rows through §5.4's law and split it as §6.2
/// writes), never through the haptic functions under test. Without a rule, the
/// reason says which precondition failed.
ClosedFormCheck closedForm(
    const Case& c, const Inputs& recorded, const Inputs& current, const std::vector<Sample>& samples);

/// @brief FNV-1a over the bytes of @p values, continuing from @p hash.
std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t hash = 1469598103934665603ull);

} // namespace voxhap::regress
