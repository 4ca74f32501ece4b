// SPDX-License-Identifier: Apache-2.0
/// @file Metrics.cpp
/// @brief The metric catalogue with its default ranges and sources, and
/// metrics.json read back.

#include "assessment/Metrics.h"

#include "core/Errors.h"
#include "core/JsonFields.h"

#include <algorithm>
#include <cmath>
#include <system_error>

namespace voxhap::assessment {

namespace fs = std::filesystem;

const std::vector<DefaultRange>& defaultRanges()
{
    // Where the seed papers give a figure it is cited; the rest are [chosen] and
    // say so. A scene's "assessment" block replaces them (data/scenes/).
    static const std::vector<DefaultRange> c{
        {"success", 1.0, std::nullopt,
            "haptic/Procedure.h: dura_intact [S19], reach_csf ([LP], [C]), reach_target within the scene's radius "
            "[chosen]"},
        {"success_dura_intact", std::nullopt, std::nullopt,
            "reported: an intact dura is the epidural procedure's rule, not every procedure's (a lumbar puncture "
            "must cross it); the senac-* scenes judge it ([S19] Sec. IV-A, physics.md §2.3)"},
        {"bone_contacts", std::nullopt, 0.0,
            "[chosen] [S19] records bone contacts among its 24 variables without a reference value; none is the "
            "careful mark"},
        {"pops", std::nullopt, std::nullopt, "the patient's layers decide the count: reported, not judged"},
        {"insertion_angle_deg", std::nullopt, 10.0,
            "[chosen] the pivot correction's design angle of 10 deg (physics.md §7 R7); no seed paper gives a "
            "tolerance"},
        {"speed_mean_mm_per_s", std::nullopt, 10.0,
            "[K01] the resistance data were recorded at a constant 1 cm/s (physics.md §1.1): faster is beyond the "
            "data the forces come from [chosen reading]"},
        {"speed_variance_mm2_per_s2", std::nullopt, 4.0,
            "[chosen] a standard deviation of 2 mm/s; [S19] Sec. IV-B: experts keep a low, constant speed, novices a "
            "variable one (no figure given)"},
        {"epidural_overshoot_mm", std::nullopt, std::nullopt,
            "the epidural space's length is the patient's: ranges come from the scene ([S19] Table I)"},
        {"syrrate_per_m", std::nullopt, std::nullopt,
            "[S19] Eq. 5 and Fig. 4 (0-20 1/m, experts higher than novices; no threshold given)"},
        {"duration_s", std::nullopt, std::nullopt, "reported, not judged"},
        {"pose_faults", std::nullopt, 0.0,
            "[chosen] a device or recording fault, not the trainee's: any one is flagged"},
    };
    return c;
}

nlohmann::json traineeMetricsJson(const haptic::TraineeMetrics& m)
{
    // The scene's success rule (haptic/Procedure.h: dura_intact, reach_csf, reach_target)
    // beside every metric of the catalogue.
    nlohmann::json j = {
        {"success_rule", haptic::successRuleName(m.outcome.rule)}, {"success_reason", m.outcome.reason}};
    for (const haptic::TraineeMetricInfo& info : haptic::traineeMetricCatalogue()) {
        const std::optional<double> v = info.value(m);
        nlohmann::json& out = j[std::string(info.key)];
        if (!v)
            out = nullptr;
        else if (info.kind == haptic::MetricKind::Flag)
            out = *v != 0.0;
        else if (info.kind == haptic::MetricKind::Count)
            out = std::int64_t(*v);
        else
            out = *v;
    }
    return j;
}

SessionMetrics sessionMetricsFromJson(const nlohmann::json& j, const std::string& origin)
{
    if (!j.is_object()) throw ValueError(origin + ": must be a JSON object (a session's metrics.json)");
    SessionMetrics s;
    s.file = origin;
    if (!j.contains("scene") || !j.at("scene").is_string() || j.at("scene").get<std::string>().empty())
        throw ValueError(origin + ": scene: missing (metrics.json names the scene of its session)");
    s.scene = j.at("scene").get<std::string>();
    for (const DefaultRange& m : defaultRanges()) {
        if (!j.contains(m.key)) continue;
        const nlohmann::json& v = j.at(m.key);
        if (v.is_null()) {
            s.values[m.key] = std::nullopt;
        } else if (v.is_boolean()) {
            s.values[m.key] = v.get<bool>() ? 1.0 : 0.0;
        } else if (v.is_number() && std::isfinite(v.get<double>())) {
            s.values[m.key] = v.get<double>();
        } else {
            throw ValueError(origin + ": " + m.key + ": must be a finite number, true/false or null");
        }
    }
    if (s.values.empty())
        throw ValueError(origin + ": no trainee metrics in it (success_dura_intact, speed_mean_mm_per_s, ...)");
    return s;
}

SessionMetrics readSessionMetrics(const fs::path& file)
{
    const nlohmann::json j = JsonFields::readFile(file, "session metrics");
    return sessionMetricsFromJson(j, file.string());
}

std::vector<fs::path> findSessionFiles(const std::vector<std::string>& inputs)
{
    std::vector<fs::path> out;
    for (const std::string& in : inputs) {
        std::error_code ec;
        const fs::path p(in);
        if (fs::is_directory(p, ec)) {
            std::vector<fs::path> found;
            for (auto it = fs::recursive_directory_iterator(p, fs::directory_options::skip_permission_denied, ec);
                 !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
                if (it->path().filename() == "metrics.json" && it->is_regular_file(ec)) found.push_back(it->path());
            }
            if (ec) throw IoError(in + ": cannot list the folder (" + ec.message() + ")");
            if (found.empty()) throw IoError(in + ": no metrics.json in this folder or below it");
            std::sort(found.begin(), found.end());
            out.insert(out.end(), found.begin(), found.end());
        } else if (fs::exists(p, ec)) {
            out.push_back(p);
        } else {
            throw IoError(in + ": no such file or folder");
        }
    }
    return out;
}

} // namespace voxhap::assessment
