// SPDX-License-Identifier: Apache-2.0
/// @file Session.cpp
#include "haptic/servo/Session.h"

#include "core/BoundedRead.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <sstream>

namespace voxhap::haptic {

namespace fs = std::filesystem;

namespace {

/// A CSV of 10 significant digits; times are written with TimeS (below) so
/// that they read back exactly.
std::function<void(std::ostream&)> csv(std::function<void(std::ostream&)> fill)
{
    return [fill = std::move(fill)](std::ostream& o) {
        o << std::setprecision(10);
        fill(o);
    };
}

/// Times with 17 significant digits: a double read back is the double written,
/// so times that increase in the session increase in the file (10 digits
/// merged 0.002999999999999999 and 0.003, and the reader refused the file).
struct TimeS {
    double value;
};
std::ostream& operator<<(std::ostream& o, TimeS t)
{
    const auto old = o.precision(17);
    o << t.value;
    o.precision(old);
    return o;
}

} // namespace

void addSessionOutputs(OutputSet& out, const Session& s, const std::vector<Layer>& layers, const fs::path& dir)
{
    fs::create_directories(dir);
    const auto layerName = [&layers](
                               int i) { return i >= 0 && i < int(layers.size()) ? layers[std::size_t(i)].name : ""; };
    out.addStream(dir / "session.csv", csv([&s, layerName](std::ostream& o) {
        o << "t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z,fx_N,fy_N,fz_N,plunger_N,depth_mm,axial_N,layer,state,"
             "fault,critical,plunger_fraction\n";
        for (const ServoRecord& r : s.records) {
            o << TimeS{r.timeS} << ',' << r.tip.x() << ',' << r.tip.y() << ',' << r.tip.z() << ',' << r.direction.x()
              << ',' << r.direction.y() << ',' << r.direction.z() << ',' << r.force.x() << ',' << r.force.y() << ','
              << r.force.z() << ',' << r.plungerN << ',' << r.depthMm << ',' << r.axialN << ',' << layerName(r.layer)
              << ',' << (r.layer >= 0 ? layerStateName(r.state) : "outside") << ',' << int(r.fault) << ','
              << int(r.critical) << ',' << r.plungerFraction << '\n';
        }
    }));
    out.addStream(dir / "events.csv", csv([&s, layerName](std::ostream& o) {
        o << "t_s,depth_mm,event,layer\n";
        for (const Event& e : s.events)
            o << TimeS{e.timeS} << ',' << e.depthMm << ',' << eventName(e.type) << ',' << layerName(e.layer) << '\n';
    }));
}

void writeSession(const Session& s, const std::vector<Layer>& layers, const fs::path& dir)
{
    OutputSet out;
    addSessionOutputs(out, s, layers, dir);
    out.commit();
}

std::vector<ServoRecord> readSessionPoses(const fs::path& file)
{
    // A regular file only (a FIFO or /dev/zero would never end); sessions are
    // read line by line, so their length is bounded by the file's, not by a limit.
    requireRegularFile(file, "session");
    std::ifstream in(file);
    if (!in) throw IoError(file.string() + ": cannot open the session");
    std::string line;
    if (!std::getline(in, line) || line.rfind("t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z", 0) != 0) {
        throw ValueError(file.string() + ": line 1: not a voxhap session (header t_s,tip_x_mm,...)");
    }
    std::vector<ServoRecord> out;
    int last = 1; // the last line read
    for (int n = 2; std::getline(in, line); ++n) {
        last = n;
        std::replace(line.begin(), line.end(), ',', ' ');
        std::istringstream ls(line);
        ServoRecord r;
        double v[7];
        for (double& x : v) {
            if (!(ls >> x) || !std::isfinite(x)) {
                throw ValueError(file.string() + ": line " + std::to_string(n) + ": bad time, tip or direction");
            }
        }
        r.timeS = v[0];
        r.tip = Vec3d(v[1], v[2], v[3]);
        r.direction = Vec3d(v[4], v[5], v[6]);
        if (!out.empty() && !(r.timeS > out.back().timeS)) {
            throw ValueError(file.string() + ": line " + std::to_string(n) + ": t_s must increase");
        }
        out.push_back(r);
    }
    if (out.size() < 2) {
        throw ValueError(file.string() + ": line " + std::to_string(last) + ": the file ends after " +
            std::to_string(out.size()) + " record(s); a session needs at least two");
    }
    return out;
}

ReplayDevice::ReplayDevice(std::vector<ServoRecord> poses, const DeviceLimits& limits)
    : mPoses(std::move(poses)), mLimits(limits)
{
    if (mPoses.size() < 2) throw ValueError("replay: a session needs at least two records");
}

DeviceReading ReplayDevice::read(double t) noexcept
{
    const double t0 = mPoses.front().timeS;
    const double tt = t + t0;
    while (mIndex + 2 < mPoses.size() && mPoses[mIndex + 1].timeS <= tt) ++mIndex;
    mFinished = tt > mPoses.back().timeS;
    const ServoRecord& a = mPoses[mIndex];
    const ServoRecord& b = mPoses[mIndex + 1];
    const double w = std::clamp((tt - a.timeS) / (b.timeS - a.timeS), 0.0, 1.0);
    DeviceReading r;
    r.tip = a.tip + w * (b.tip - a.tip);
    const Vec3d d = a.direction + w * (b.direction - a.direction);
    r.direction = d.norm() > 0.0 ? Vec3d(d.normalized()) : a.direction;
    r.velocity = (b.tip - a.tip) / (b.timeS - a.timeS);
    r.valid = true;
    return r;
}

TraineeMetrics traineeMetrics(const Session& s, const std::vector<Layer>& layers, const Vec3d& pathDirection)
{
    TraineeMetrics m;
    double skinT = kNoLimit, skinDepth = 0.0;
    for (const Event& e : s.events) {
        if (e.type == EventType::DuraPuncture) m.success = false;
        if (e.type == EventType::BoneContact) ++m.boneContacts;
        if (e.type == EventType::Pop) ++m.pops;
        if (e.type == EventType::SkinEntry && !std::isfinite(skinT)) skinT = e.timeS, skinDepth = e.depthMm;
    }
    const Vec3d u = pathDirection.normalized();
    double sum = 0, sum2 = 0, epidural = 0;
    long n = 0;
    bool inEpidural = false;
    // A record is a fault when no hand on the device could have produced it; the
    // figures then skip it, comparing the next good record with the last good one.
    std::vector<char> good(s.records.size(), 0);
    for (std::size_t i = 0; i < s.records.size(); ++i) {
        const ServoRecord& r = s.records[i];
        good[i] = r.tip.allFinite() && std::isfinite(r.depthMm) && std::isfinite(r.timeS) &&
            (r.tip - s.records.front().tip).norm() <= kWorkspaceReachMm;
    }
    std::size_t last = s.records.size();
    for (std::size_t i = 0; i < s.records.size(); ++i) {
        if (!good[i]) continue;
        if (last < s.records.size()) {
            const double dt = s.records[i].timeS - s.records[last].timeS;
            if (dt > 0.0 && (s.records[i].tip - s.records[last].tip).norm() / dt > kMaxHandSpeedMmPerS) {
                good[i] = 0; // a jump: keep comparing with the last good record
                continue;
            }
        }
        last = i;
    }
    for (const char g : good) m.poseFaults += !g;
    std::size_t prev = s.records.size();
    for (std::size_t i = 0; i < s.records.size(); ++i) {
        if (!good[i]) continue;
        if (prev == s.records.size()) {
            prev = i;
            continue;
        }
        const ServoRecord& a = s.records[prev];
        const ServoRecord& b = s.records[i];
        prev = i;
        if (!m.insertionAngleDeg && b.timeS >= skinT) {
            m.insertionAngleDeg = std::acos(std::clamp(b.direction.normalized().dot(u), -1.0, 1.0)) * 180.0 / kPi;
        }
        const double dt = b.timeS - a.timeS;
        const double v = dt > 0.0 ? (b.depthMm - a.depthMm) / dt : 0.0;
        if (b.timeS >= skinT && v > 0.0) sum += v, sum2 += v * v, ++n;
        const bool epi =
            b.layer >= 0 && b.layer < int(layers.size()) && layers[std::size_t(b.layer)].role == LayerRole::Epidural;
        if (epi) epidural += std::abs(b.depthMm - a.depthMm), inEpidural = true;
    }
    if (inEpidural) m.overshootMm = epidural;
    if (n > 0) {
        m.speedMeanMmPerS = sum / double(n);
        m.speedVarianceMm2PerS2 = std::max(0.0, sum2 / double(n) - m.speedMeanMmPerS * m.speedMeanMmPerS);
    }
    if (!s.records.empty()) m.durationS = s.records.back().timeS - s.records.front().timeS;
    // syrrate ([S19], §2.3): syringe fraction emptied from the derma's puncture to the
    // end, per metre travelled along the path in that time.
    if (std::isfinite(skinT) && !s.records.empty() && std::isfinite(s.records.back().plungerFraction)) {
        double startFraction = 0.0;
        for (const ServoRecord& r : s.records) {
            if (r.timeS >= skinT) {
                startFraction = std::isfinite(r.plungerFraction) ? r.plungerFraction : 0.0;
                break;
            }
        }
        const double travelM = (s.records.back().depthMm - skinDepth) * 1e-3;
        if (travelM > 0.0) m.syrrate = (s.records.back().plungerFraction - startFraction) / travelM;
    }
    return m;
}

} // namespace voxhap::haptic
