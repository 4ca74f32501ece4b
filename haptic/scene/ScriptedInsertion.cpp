// SPDX-License-Identifier: Apache-2.0
/// @file Insertion.cpp
#include "haptic/scene/ScriptedInsertion.h"

#include "core/AtomicFile.h"
#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "core/Format.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <limits>
#include <sstream>

namespace voxhap::haptic {

InsertionScript InsertionScript::constantSpeed(double from, double to, double speed)
{
    if (!(speed > 0.0) || !std::isfinite(speed)) throw ValueError("insertion: speed must be positive");
    if (!std::isfinite(from) || !std::isfinite(to)) throw ValueError("insertion: depths must be finite");
    return InsertionScript{{{0.0, from}, {std::abs(to - from) / speed, to}}};
}

InsertionScript InsertionScript::load(const std::filesystem::path& file)
{
    std::istringstream in(readBoundedFile(file, "insertion script")); // regular, at most 16 MiB
    InsertionScript s;
    std::string line;
    for (int n = 1; std::getline(in, line); ++n) {
        if (line.empty() || line[0] == '#' ||
            (n == 1 && !std::isdigit(static_cast<unsigned char>(line[0])) && line[0] != '-'))
            continue;
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream ls(line);
        double t = 0, d = 0, roll = 0;
        std::string rest;
        const bool rolls = s.knots.empty() ? bool(ls >> t >> d >> roll) : !s.rollsDeg.empty();
        if (s.knots.empty()) ls = std::istringstream(line);
        const bool ok = rolls ? bool(ls >> t >> d >> roll) : bool(ls >> t >> d);
        if (!ok || (ls >> rest) || !std::isfinite(t) || !std::isfinite(d) || !std::isfinite(roll)) {
            throw ValueError(file.string() + ": line " + std::to_string(n) + ": expected \"t_s,depth_mm" +
                (rolls ? ",roll_deg" : "") + "\"" + (s.knots.empty() ? "" : " as on the first row"));
        }
        if (!s.knots.empty() && !(t > s.knots.back().first)) {
            throw ValueError(file.string() + ": line " + std::to_string(n) + ": t_s must increase");
        }
        s.knots.emplace_back(t, d);
        if (rolls) s.rollsDeg.push_back(roll);
    }
    if (s.knots.size() < 2) throw ValueError(file.string() + ": an insertion script needs at least two rows");
    if (s.knots.front().first != 0.0) throw ValueError(file.string() + ": line 1: the script must start at t_s = 0");
    return s;
}

namespace {
std::size_t segmentOf(const InsertionScript& s, double t)
{
    std::size_t i = 1;
    while (i + 1 < s.knots.size() && t > s.knots[i].first) ++i;
    return i;
}
} // namespace

double InsertionScript::depthAt(double t) const
{
    if (knots.empty()) return 0.0;
    if (t <= knots.front().first) return knots.front().second;
    if (t >= knots.back().first) return knots.back().second;
    const std::size_t i = segmentOf(*this, t);
    const auto [t0, d0] = knots[i - 1];
    const auto [t1, d1] = knots[i];
    return d0 + (d1 - d0) * (t - t0) / (t1 - t0);
}

double InsertionScript::speedAt(double t) const
{
    if (knots.size() < 2 || t < 0.0 || t > knots.back().first) return 0.0;
    const std::size_t i = segmentOf(*this, t);
    return (knots[i].second - knots[i - 1].second) / (knots[i].first - knots[i - 1].first);
}

double InsertionScript::rollAt(double t) const
{
    if (rollsDeg.size() != knots.size() || knots.empty()) return std::numeric_limits<double>::quiet_NaN();
    if (t <= knots.front().first) return degToRad(rollsDeg.front());
    if (t >= knots.back().first) return degToRad(rollsDeg.back());
    const std::size_t i = segmentOf(*this, t);
    const double t0 = knots[i - 1].first, t1 = knots[i].first;
    return degToRad(rollsDeg[i - 1] + (rollsDeg[i] - rollsDeg[i - 1]) * (t - t0) / (t1 - t0));
}

InsertionResult runInsertion(NeedleForceModel& model, const InsertionScript& script, double rateHz,
    const SuccessCriteria& success, std::optional<Vec3d> target)
{
    if (!(rateHz > 0.0) || !std::isfinite(rateHz)) throw ValueError("insertion: rate must be positive");
    InsertionResult r;
    const double dt = 1.0 / rateHz;
    const long ticks = long(std::ceil(script.duration() * rateHz - 1e-9)) + 1;
    r.rows.reserve(std::size_t(ticks));
    const NeedlePath& path = model.path();
    NeedleOutput out;
    InsertionSummary& s = r.summary;
    OutcomeTracker outcome(success, model.layers(), target);
    for (long n = 0; n < ticks; ++n) {
        const double t = std::min(double(n) * dt, script.duration());
        NeedleInput in;
        in.timeS = t;
        in.dtS = dt;
        in.tip = path.origin + script.depthAt(t) * path.direction;
        in.direction = path.direction;
        in.velocity = script.speedAt(t) * path.direction;
        in.rollRad = script.rollAt(t);
        model.step(in, out);
        InsertionRow row;
        row.timeS = t;
        row.depthMm = out.tip.depthMm;
        row.speedMmPerS = out.speedMmPerS;
        row.force = out.force;
        row.axialN = out.axialN;
        row.plungerN = out.plungerN;
        row.layer = out.tip.currentLayer();
        row.state = row.layer >= 0 ? model.state().state(row.layer) : LayerState::Intact;
        row.critical = out.critical;
        row.fault = out.fault;
        row.firstEvent = int(r.events.size());
        row.eventCount = out.events.size();
        for (const Event& e : out.events) {
            r.events.push_back(e);
            outcome.addEvent(e);
            switch (e.type) {
            case EventType::SkinEntry:
                s.skinEntryMm = std::min(s.skinEntryMm, e.depthMm);
                break;
            case EventType::Pop:
                ++s.pops;
                break;
            case EventType::LossOfResistance:
                s.lorMm = std::min(s.lorMm, e.depthMm);
                break;
            case EventType::DuraPuncture:
                s.duraMm = std::min(s.duraMm, e.depthMm);
                break;
            case EventType::BoneContact:
                ++s.boneContacts, s.boneMm = std::min(s.boneMm, e.depthMm);
                break;
            case EventType::CriticalBreach:
                ++s.breaches, s.breachMm = std::min(s.breachMm, e.depthMm);
                break;
            case EventType::Fault:
                ++s.faults;
                break;
            case EventType::ForceLimited:
                ++s.forceLimits, s.firstLimitMm = std::min(s.firstLimitMm, e.depthMm);
                break;
            default:
                break;
            }
        }
        outcome.addTip(in.tip, row.layer);
        if (out.limitedN > 0.0) ++s.limitedTicks, s.maxLimitedN = std::max(s.maxLimitedN, out.limitedN);
        s.peakModelN = std::max(s.peakModelN, out.modelForce.norm());
        s.peakRenderedN = std::max(s.peakRenderedN, out.force.norm());
        s.peakPlungerN = std::max(s.peakPlungerN, out.plungerN);
        if (const Guidance* g = model.guidance()) {
            s.guidance = true;
            s.peakGuidanceN = std::max(s.peakGuidanceN, out.terms.guidance.norm());
            s.maxOffsetMm = std::max(s.maxOffsetMm, g->offset(in.tip).norm());
        }
        if (const BentNeedle* b = model.bentNeedle()) {
            // The bent tip off the straight line the hand drives along (physics.md §9.6).
            const Vec3d off = b->tip() - path.origin;
            s.bending = true;
            s.tipDeviationMm = (off - off.dot(path.direction) * path.direction).norm();
            s.maxTipDeviationMm = std::max(s.maxTipDeviationMm, s.tipDeviationMm);
        }
        r.rows.push_back(row);
    }
    if (const BentNeedle* b = model.bentNeedle()) r.bentShaft.assign(b->shaft().begin(), b->shaft().end());
    s.finalDepthMm = r.rows.empty() ? 0.0 : r.rows.back().depthMm;
    s.durationS = script.duration();
    r.outcome = outcome.result();
    return r;
}

void writeInsertionCsv(const InsertionResult& r, const std::vector<Layer>& layers, const std::filesystem::path& file)
{
    writeStreamAtomically(file, [&](std::ostream& o) {
        o << "t_s,depth_mm,speed_mm_per_s,fx_N,fy_N,fz_N,force_N,axial_model_N,plunger_N,state,layer,events\n";
        o << std::setprecision(9);
        for (const InsertionRow& row : r.rows) {
            o << row.timeS << ',' << row.depthMm << ',' << row.speedMmPerS << ',' << row.force.x() << ','
              << row.force.y() << ',' << row.force.z() << ',' << row.force.norm() << ',' << row.axialN << ','
              << row.plungerN << ',' << (row.layer >= 0 ? layerStateName(row.state) : "outside") << ','
              << (row.layer >= 0 ? layers[std::size_t(row.layer)].name : "") << ',';
            for (int k = 0; k < row.eventCount; ++k)
                o << (k ? ";" : "") << eventName(r.events[std::size_t(row.firstEvent + k)].type);
            o << '\n';
        }
    });
}

std::string insertionSummaryText(const InsertionResult& r, const std::vector<Layer>& layers)
{
    const InsertionSummary& s = r.summary;
    std::ostringstream o;
    o << std::fixed << std::setprecision(1);
    // Depths through fixed(): a surface met at -1e-15 mm prints "0.0", never "-0.0".
    const auto at = [&](const char* what, double d) {
        o << "  " << std::left << std::setw(20) << what;
        if (std::isfinite(d))
            o << "at " << fixed(d) << " mm\n";
        else
            o << "none\n";
    };
    at("skin puncture", s.skinEntryMm);
    o << "  " << std::left << std::setw(20) << "pops" << s.pops;
    bool firstPop = true;
    for (const Event& e : r.events) {
        if (e.type == EventType::Pop) {
            o << (firstPop ? " " : "  ") << layers[std::size_t(e.layer)].name << " " << fixed(e.depthMm);
            firstPop = false;
        }
    }
    o << '\n';
    at("loss of resistance", s.lorMm);
    at("dura puncture", s.duraMm);
    at("bone contact", s.boneMm);
    at("critical breach", s.breachMm);
    o << std::setprecision(2);
    o << "  " << std::setw(20) << "peak force" << s.peakModelN << " N model, " << s.peakRenderedN << " N rendered\n";
    if (s.peakPlungerN > 0.0) o << "  " << std::setw(20) << "peak plunger" << s.peakPlungerN << " N\n";
    if (s.forceLimits > 0) { // §6.3: where the device's limits flattened the profile
        o << "  " << std::setw(20) << "force limited" << s.forceLimits << (s.forceLimits == 1 ? " time" : " times")
          << " from " << fixed(s.firstLimitMm) << " mm, " << s.limitedTicks << " ticks, up to "
          << fixed(s.maxLimitedN, 2) << " N cut by the device limits\n";
    } else {
        o << "  " << std::setw(20) << "force limited"
          << "never\n";
    }
    if (s.faults) o << "  " << std::setw(20) << "faults" << s.faults << '\n';
    if (s.guidance) {
        o << "  " << std::setw(20) << "guidance" << s.peakGuidanceN << " N peak pull, " << s.maxOffsetMm
          << " mm largest offset from the planned line\n";
    }
    if (s.bending) {
        o << "  " << std::setw(20) << "tip deviation" << fixed(s.tipDeviationMm, 2)
          << " mm from the straight line at the end, " << fixed(s.maxTipDeviationMm, 2) << " mm at most\n";
    }
    o << std::setprecision(1) << "  " << std::setw(20) << "inserted" << fixed(s.finalDepthMm) << " mm in "
      << s.durationS << " s\n";
    o << "  " << std::setw(20) << "success" << (r.outcome.success ? "yes" : "no") << " ("
      << successRuleName(r.outcome.rule) << "): " << r.outcome.reason << '\n';
    return o.str();
}

} // namespace voxhap::haptic
