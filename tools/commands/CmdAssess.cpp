// SPDX-License-Identifier: Apache-2.0
/// @file CmdAssess.cpp
/// @brief `voxhap assess`: sessions' metrics.json against reference ranges, pass or
/// flag per metric; a logistic-regression classifier trained on labelled metrics
/// with cross-validated accuracy; simulated cohorts to try it on.
///
/// Exit codes: 0 every judged metric of every session passed (or only training or
/// a simulated cohort was asked for), 3 at least one metric was flagged, 1 bad
/// input (a file, a field), 2 bad arguments.

#include "tools/Cli.h"

#include "assessment/Assess.h"
#include "assessment/Classifier.h"
#include "assessment/LabelledCsv.h"
#include "assessment/SimulatedCohort.h"
#include "core/AtomicFile.h"
#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/JsonFields.h"
#include "haptic/scene/Scene.h"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

namespace voxhap::tools {

namespace {

namespace fs = std::filesystem;
using namespace voxhap::assessment;

constexpr int kExitFlagged = 3;

struct AssessOptions {
    CommonOptions common;
    std::vector<std::string> sessions;
    std::string scene, model, train, saveModel, out = "voxhap-cohort";
    int folds = 5, cohort = 0;
    double lambda = 1.0;
};

std::string valueText(const MetricResult& m)
{
    if (!m.value) return "null";
    const haptic::TraineeMetricInfo* info = haptic::findTraineeMetric(m.range.metric);
    if (info && info->kind == haptic::MetricKind::Flag) return *m.value != 0.0 ? "true" : "false";
    std::ostringstream os;
    os << std::setprecision(4) << *m.value;
    return os.str();
}

std::string rangeText(const ReferenceRange& r)
{
    const haptic::TraineeMetricInfo* info = haptic::findTraineeMetric(r.metric);
    if (info && info->kind == haptic::MetricKind::Flag)
        return r.min && *r.min > 0 ? "true" : r.max && *r.max < 1 ? "false" : "-";
    std::ostringstream os;
    os << std::setprecision(4);
    if (r.min && r.max)
        os << *r.min << " .. " << *r.max;
    else if (r.min)
        os << ">= " << *r.min;
    else if (r.max)
        os << "<= " << *r.max;
    else
        os << "-";
    return os.str();
}

int run(const AssessOptions& o, const CLI::App& cmd)
{
    if (o.sessions.empty() && o.train.empty() && o.cohort == 0)
        throw UsageError("give sessions' metrics.json (files or folders), --train labelled.csv or --simulate-cohort N");
    if (!o.saveModel.empty() && o.train.empty()) throw UsageError("--save-model needs --train");
    if (!o.model.empty() && !o.train.empty())
        throw UsageError("--model and --train: give one (--train makes the model)");
    if (o.cohort > 0 && o.scene.empty()) throw UsageError("--simulate-cohort needs --scene");
    if (cmd.count("--folds") && o.train.empty()) throw UsageError("--folds needs --train");
    const volume::TissueTable& table = tissueTable(o.common);
    nlohmann::json report = nlohmann::json::object();

    if (o.cohort > 0) report.update(writeSimulatedCohort(loadSceneSayingDefaults(o.scene), table, o.cohort, o.out));

    std::optional<LogisticModel> model;
    std::string modelName;
    if (!o.train.empty()) {
        const LabelledSet data = readLabelledCsv(o.train);
        TrainOptions to;
        to.lambda = o.lambda;
        const CrossValidation cv = crossValidate(data, o.folds, to);
        model = trainLogistic(data, to);
        modelName = o.train;
        nlohmann::json mj = model->toJson();
        mj["trained_on"] = fs::path(o.train).filename().string();
        mj["samples"] = data.x.size();
        mj["cross_validation"] = {{"folds", cv.folds}, {"correct", cv.correct}, {"n", cv.n}, {"accuracy", cv.accuracy},
            {"ci95", {cv.ci95.low, cv.ci95.high}}, {"interval", "Wilson score, 95 %"}};
        report["classifier"] = mj;
        if (!o.saveModel.empty()) {
            const std::string text = mj.dump(2) + "\n";
            OutputSet outputs;
            outputs.addStream(o.saveModel, [text](std::ostream& out) { out << text; });
            outputs.commit();
        }
    } else if (!o.model.empty()) {
        model = LogisticModel::fromJson(JsonFields::readFile(o.model, "assessment model"), o.model);
        modelName = o.model;
    }

    int flaggedSessions = 0;
    if (!o.sessions.empty()) {
        std::optional<haptic::Scene> given;
        if (!o.scene.empty()) given = loadSceneSayingDefaults(o.scene);
        std::map<std::string, std::vector<ReferenceRange>> rangesOf; // by scene name
        nlohmann::json all = nlohmann::json::array();
        for (const fs::path& file : findSessionFiles(o.sessions)) {
            const SessionMetrics s = readSessionMetrics(file);
            const std::string key = given ? given->name : s.scene;
            if (!rangesOf.count(key)) {
                if (given) {
                    rangesOf[key] = referenceRanges(&*given);
                } else {
                    std::optional<haptic::Scene> sc;
                    try {
                        sc = haptic::loadScene(s.scene);
                    } catch (const std::exception& e) {
                        throw ValueError(file.string() + ": scene: '" + s.scene +
                            "' is not a built-in scene or a scene file here (" + e.what() + "); name one with --scene");
                    }
                    rangesOf[key] = referenceRanges(&*sc);
                }
            }
            const SessionAssessment a = assessSession(s, rangesOf[key]);
            nlohmann::json j = toJson(a);
            if (model) {
                const double p = model->probability(modelFeatures(s, *model, modelName));
                j["classifier"] = {{"probability_label_1", p}, {"predicted_label", p >= 0.5 ? 1 : 0}};
            }
            flaggedSessions += a.flagged() > 0;
            all.push_back(std::move(j));
        }
        report["sessions"] = all;
        report["flagged_sessions"] = flaggedSessions;
    }

    if (o.common.json) {
        std::cout << report.dump(2) << '\n';
        return flaggedSessions ? kExitFlagged : 0;
    }
    if (report.contains("simulated_cohort")) {
        const auto& c = report["simulated_cohort"];
        std::cout << "simulated cohort (simulated hands, not real trainees): " << c["sessions"].get<int>()
                  << " sessions on " << c["scene"].get<std::string>() << "\n  " << c["labelled_csv"].get<std::string>()
                  << "\n  " << (fs::path(o.out) / "<session>" / "metrics.json").string() << "\n";
    }
    if (report.contains("classifier") && !o.train.empty()) {
        const auto& cv = report["classifier"]["cross_validation"];
        std::cout << "classifier: logistic regression (lambda " << o.lambda << ") on " << model->features.size()
                  << " features, " << report["classifier"]["samples"].get<int>() << " labelled sessions of " << o.train
                  << "\n  " << cv["folds"].get<int>() << "-fold cross-validated accuracy " << std::fixed
                  << std::setprecision(3) << cv["accuracy"].get<double>() << " (" << cv["correct"].get<int>() << "/"
                  << cv["n"].get<int>() << "), Wilson 95 % interval " << cv["ci95"][0].get<double>() << " .. "
                  << cv["ci95"][1].get<double>() << "\n";
        std::cout.unsetf(std::ios::fixed);
        if (!o.saveModel.empty()) std::cout << "  model written to " << o.saveModel << "\n";
    }
    if (report.contains("sessions")) {
        const auto& all = report["sessions"];
        std::cout << "assessed " << all.size() << " session" << (all.size() == 1 ? "" : "s") << ": " << flaggedSessions
                  << " with a flagged metric\n";
        for (const auto& j : all) {
            std::cout << "\n"
                      << j["file"].get<std::string>() << " (scene " << j["scene"].get<std::string>()
                      << "): " << j["flagged"].get<int>() << " flagged, " << j["passed"].get<int>() << " passed\n";
            std::cout << "  " << std::left << std::setw(27) << "metric" << std::setw(10) << "value" << std::setw(16)
                      << "range" << std::setw(14) << "verdict"
                      << "range source\n";
            for (const auto& m : j["metrics"]) {
                MetricResult r;
                r.range.metric = m["metric"].get<std::string>();
                if (!m["value"].is_null()) r.value = m["value"].get<double>();
                if (!m["min"].is_null()) r.range.min = m["min"].get<double>();
                if (!m["max"].is_null()) r.range.max = m["max"].get<double>();
                std::cout << "  " << std::setw(27) << r.range.metric << std::setw(10) << valueText(r) << std::setw(16)
                          << rangeText(r.range) << std::setw(14) << m["verdict"].get<std::string>()
                          << m["source"].get<std::string>() << " (" << m["range_from"].get<std::string>() << ")\n";
            }
            if (j.contains("classifier")) {
                std::cout << "  classifier: P(label 1) = " << std::setprecision(3)
                          << j["classifier"]["probability_label_1"].get<double>() << " ("
                          << (model && !o.train.empty() ? o.train : o.model) << ")\n";
            }
            std::cout << std::right;
        }
    }
    return flaggedSessions ? kExitFlagged : 0;
}

} // namespace

Action registerAssess(CLI::App& app)
{
    auto o = std::make_shared<AssessOptions>();
    CLI::App* cmd = app.add_subcommand("assess",
        "Assess trainee sessions: each metric of metrics.json against the scene's reference ranges (pass or flag); "
        "train a logistic-regression classifier on labelled metrics with cross-validated accuracy. Exit 0 all "
        "passed, 3 a metric flagged, 1 bad input, 2 bad arguments");
    cmd->add_option("sessions", o->sessions,
        "Sessions: metrics.json files (as `voxhap serve` writes them) or folders searched for them");
    cmd->add_option("--scene", o->scene,
        "Judge every session by this scene's ranges (default: the scene each metrics.json names); the scene of "
        "--simulate-cohort");
    cmd->add_option("--train", o->train,
        "Labelled CSV: a header, a 'label' column (0/1), an optional 'session' column, metric columns; trains the "
        "classifier and prints its cross-validated accuracy");
    cmd->add_option("--folds", o->folds, "Cross-validation folds (default 5)")->check(CLI::Range(2, 1000000));
    cmd->add_option(
           "--lambda", o->lambda, "L2 penalty of the logistic regression (default 1; 0: plain maximum likelihood)")
        ->check(CLI::Range(0.0, 1e9));
    cmd->add_option("--save-model", o->saveModel, "Write the trained model (JSON) here");
    cmd->add_option("--model", o->model, "A model saved with --save-model: classify the sessions with it");
    cmd->add_option("--simulate-cohort", o->cohort,
           "Simulate N careful and N reckless simulated hands on --scene; write OUT/<id>/metrics.json and "
           "OUT/labelled.csv (simulated, not real trainees)")
        ->check(CLI::Range(2, 1000));
    cmd->add_option("--out,-o", o->out, "Folder of --simulate-cohort (default voxhap-cohort)");
    addCommonOptions(*cmd, o->common);
    return [o, cmd] { return run(*o, *cmd); };
}

} // namespace voxhap::tools
