// SPDX-License-Identifier: Apache-2.0
/// @file SimulatedCohort.cpp
/// @brief Simulated hands run in simulated time, and their metrics.

#include "assessment/SimulatedCohort.h"

#include "assessment/LabelledCsv.h"
#include "assessment/Metrics.h"
#include "core/AtomicFile.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/Session.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

namespace voxhap::assessment {

std::vector<SimulatedTrainee> simulatedCohort(const CohortSpec& spec)
{
    std::mt19937 rng(spec.seed);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const auto between = [&](double a, double b) { return a + (b - a) * unit(rng); };
    std::vector<SimulatedTrainee> out;
    for (int kind = 0; kind < 2; ++kind) {
        const bool careful = kind == 0;
        for (int i = 0; i < spec.perClass; ++i) {
            SimulatedTrainee t;
            char id[32];
            std::snprintf(id, sizeof id, "%s-%02d", careful ? "careful" : "reckless", i + 1);
            t.id = id;
            t.careful = careful;
            haptic::HandParams& h = t.hand;
            h.speedMmPerS = careful ? between(spec.carefulMinMmPerS, spec.carefulMaxMmPerS)
                                    : between(spec.recklessMinMmPerS, spec.recklessMaxMmPerS);
            h.gripNPerMm = between(0.8, 1.4);
            h.dampingNsPerMm = 2.0 * std::sqrt(h.gripNPerMm * h.massKg * 1e-3); // critical: 2·sqrt(k·m), N·s/mm
            h.reactionS = between(0.15, 0.35);
            h.stopOnLor = careful;
            h.startMm = -spec.approachMm;
            h.maxDepthMm = spec.maxDepthMm;
            // Long enough for the set point to reach its end and the hand to settle.
            t.seconds = (spec.maxDepthMm + spec.approachMm) / h.speedMmPerS + 2.0;
            out.push_back(std::move(t));
        }
    }
    return out;
}

nlohmann::json simulateSession(const haptic::SceneInstance& inst, const SimulatedTrainee& t)
{
    auto model = inst.makeModel();
    haptic::HandDevice hand(model->path(), t.hand, model->device());
    haptic::ServoOptions so;
    so.rateHz = inst.scene().rateHz;
    haptic::ServoLoop loop(*model, hand, so);
    haptic::TraineeMetricsAccumulator acc(model->layers(), model->path().direction);
    const long total = long(std::llround(t.seconds * so.rateHz));
    // In chunks well inside the loop's queues; each chunk's events go in before the
    // first of its records at or after their time, as the session recorder does.
    constexpr long kChunk = 1000;
    std::vector<haptic::ServoRecord> records;
    std::vector<haptic::Event> events;
    for (long done = 0; done < total; done += kChunk) {
        loop.runTicks(std::min(kChunk, total - done));
        records.clear();
        events.clear();
        haptic::ServoRecord r;
        haptic::Event e;
        while (loop.popRecord(r)) records.push_back(r);
        while (loop.popEvent(e)) events.push_back(e);
        std::size_t k = 0;
        for (const haptic::ServoRecord& rec : records) {
            while (k < events.size() && events[k].timeS <= rec.timeS) acc.addEvent(events[k++]);
            acc.addRecord(rec);
        }
        while (k < events.size()) acc.addEvent(events[k++]);
    }
    nlohmann::json j = traineeMetricsJson(acc.result());
    j["scene"] = inst.scene().name;
    j["device"] = hand.name();
    j["simulated"] = true;
    j["trainee"] = t.id;
    j["hand_speed_mm_per_s"] = t.hand.speedMmPerS;
    j["ticks"] = total;
    j["dropped_records"] = loop.droppedRecords();
    return j;
}

nlohmann::json writeSimulatedCohort(
    const haptic::Scene& scene, const volume::TissueTable& table, int perClass, const std::filesystem::path& out)
{
    namespace fs = std::filesystem;
    const haptic::SceneInstance inst(scene, nullptr, table);
    CohortSpec spec;
    spec.perClass = perClass;
    spec.approachMm = scene.approachMm;
    std::vector<nlohmann::json> sessions;
    for (const SimulatedTrainee& t : simulatedCohort(spec)) sessions.push_back(simulateSession(inst, t));
    // Columns: the catalogue's metrics that every simulated session measured.
    std::vector<std::string> columns;
    for (const DefaultRange& m : defaultRanges()) {
        if (m.key == "duration_s" || m.key == "pose_faults") continue; // the session's length; faults are not skill
        bool all = true;
        for (const auto& j : sessions) all = all && j.contains(m.key) && !j.at(m.key).is_null();
        if (all) columns.push_back(m.key);
    }
    std::vector<LabelledRow> rows;
    OutputSet outputs; // every session's metrics.json and the table, together
    for (const auto& j : sessions) {
        const std::string id = j.at("trainee").get<std::string>();
        rows.push_back({id, id.rfind("reckless", 0) == 0 ? 1 : 0, j});
        const std::string text = j.dump(2) + "\n";
        fs::create_directories(out / id);
        outputs.addStream(out / id / "metrics.json", [text](std::ostream& os) { os << text; });
    }
    const std::string table_ = labelledCsvText(rows, columns,
        "simulated cohort: careful (label 0) and reckless (label 1) simulated hands on scene " + scene.name +
            "; not real trainees");
    outputs.addStream(out / "labelled.csv", [table_](std::ostream& os) { os << table_; });
    outputs.commit();
    return {{"simulated_cohort",
        {{"scene", scene.name}, {"sessions", sessions.size()}, {"labelled_csv", (out / "labelled.csv").string()},
            {"note", "simulated hands, not real trainees"}}}};
}

} // namespace voxhap::assessment
