// SPDX-License-Identifier: Apache-2.0
/// @file Session.cpp
#include "haptic/servo/Session.h"

#include "core/BoundedRead.h"

#include "core/AtomicFile.h"
#include "core/Errors.h"
#include "haptic/servo/ServoLoop.h"

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

constexpr const char* kSessionHeader =
    "t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z,fx_N,fy_N,fz_N,plunger_N,depth_mm,axial_N,layer,state,"
    "fault,critical,plunger_fraction\n";
constexpr const char* kEventsHeader = "t_s,depth_mm,event,layer\n";

/// A reference, not a copy: a recorder writes a row per tick and must not allocate for it.
const std::string& layerNameOf(const std::vector<Layer>& layers, int i)
{
    static const std::string none;
    return i >= 0 && i < int(layers.size()) ? layers[std::size_t(i)].name : none;
}

/// One session.csv row (the stream is at 10 significant digits).
void writeRecordRow(std::ostream& o, const ServoRecord& r, const std::vector<Layer>& layers)
{
    o << TimeS{r.timeS} << ',' << r.tip.x() << ',' << r.tip.y() << ',' << r.tip.z() << ',' << r.direction.x() << ','
      << r.direction.y() << ',' << r.direction.z() << ',' << r.force.x() << ',' << r.force.y() << ',' << r.force.z()
      << ',' << r.plungerN << ',' << r.depthMm << ',' << r.axialN << ',' << layerNameOf(layers, r.layer) << ','
      << (r.layer >= 0 ? layerStateName(r.state) : "outside") << ',' << int(r.fault) << ',' << int(r.critical) << ','
      << r.plungerFraction << '\n';
}

void writeEventRow(std::ostream& o, const Event& e, const std::vector<Layer>& layers)
{
    o << TimeS{e.timeS} << ',' << e.depthMm << ',' << eventName(e.type) << ',' << layerNameOf(layers, e.layer) << '\n';
}

/// session.csv's closing line: a comment (readers skip lines that start with '#',
/// as pandas does with comment='#') that states what the file holds.
void writeSessionTrailer(std::ostream& o, long records, long dropped)
{
    o << "# " << records << " records written, " << dropped
      << " dropped (the servo loop's record queue was full; the tick went on)\n";
}

} // namespace

void addSessionOutputs(OutputSet& out, const Session& s, const std::vector<Layer>& layers, const fs::path& dir)
{
    fs::create_directories(dir);
    out.addStream(dir / "session.csv", csv([&s, &layers](std::ostream& o) {
        o << kSessionHeader;
        for (const ServoRecord& r : s.records) writeRecordRow(o, r, layers);
        writeSessionTrailer(o, long(s.records.size()), 0);
    }));
    out.addStream(dir / "events.csv", csv([&s, &layers](std::ostream& o) {
        o << kEventsHeader;
        for (const Event& e : s.events) writeEventRow(o, e, layers);
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
        if (line.rfind('#', 0) == 0) continue; // a comment (the closing line states the counts)
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

TraineeMetricsAccumulator::TraineeMetricsAccumulator(const std::vector<Layer>& layers, const Vec3d& pathDirection,
    const SuccessCriteria& success, std::optional<Vec3d> target)
    : mLayers(layers), mDirection(pathDirection.normalized()), mOutcome(success, layers, target), mSkinT(kNoLimit)
{
}

void TraineeMetricsAccumulator::addEvent(const Event& e) noexcept
{
    mOutcome.addEvent(e);
    if (e.type == EventType::DuraPuncture) mM.duraIntact = false;
    if (e.type == EventType::ForceLimited) ++mM.forceLimits;
    if (e.type == EventType::BoneContact) ++mM.boneContacts;
    if (e.type == EventType::Pop) ++mM.pops;
    if (e.type == EventType::SkinEntry && !std::isfinite(mSkinT)) mSkinT = e.timeS, mSkinDepth = e.depthMm;
}

void TraineeMetricsAccumulator::addRecord(const ServoRecord& r) noexcept
{
    if (!mHaveFirst) mFirst = r, mHaveFirst = true;
    mLast = r;
    // syrrate's starting fraction: the first record from the skin's puncture on.
    if (!mHaveStartFraction && r.timeS >= mSkinT) {
        mStartFraction = std::isfinite(r.plungerFraction) ? r.plungerFraction : 0.0;
        mHaveStartFraction = true;
    }
    // A record is a fault when no hand on the device could have produced it: a
    // non-finite tip, one beyond the workspace's reach of the first tip, or a
    // jump faster than a hand from the last good record. The figures skip it,
    // comparing the next good record with the last good one.
    bool good = r.tip.allFinite() && std::isfinite(r.depthMm) && std::isfinite(r.timeS) &&
        (r.tip - mFirst.tip).norm() <= kWorkspaceReachMm;
    if (good && mHavePrev) {
        const double dt = r.timeS - mPrevGood.timeS;
        if (dt > 0.0 && (r.tip - mPrevGood.tip).norm() / dt > kMaxHandSpeedMmPerS) good = false;
    }
    if (!good) {
        ++mM.poseFaults;
        return;
    }
    mOutcome.addTip(r.tip, r.layer);
    if (!mHavePrev) {
        mPrevGood = r;
        mHavePrev = true;
        return;
    }
    const ServoRecord& a = mPrevGood;
    const ServoRecord& b = r;
    if (!mM.insertionAngleDeg && b.timeS >= mSkinT) {
        mM.insertionAngleDeg = std::acos(std::clamp(b.direction.normalized().dot(mDirection), -1.0, 1.0)) * 180.0 / kPi;
    }
    const double dt = b.timeS - a.timeS;
    const double v = dt > 0.0 ? (b.depthMm - a.depthMm) / dt : 0.0;
    if (b.timeS >= mSkinT && v > 0.0) mSum += v, mSum2 += v * v, ++mN;
    const bool epi =
        b.layer >= 0 && b.layer < int(mLayers.size()) && mLayers[std::size_t(b.layer)].role == LayerRole::Epidural;
    if (epi) mEpidural += std::abs(b.depthMm - a.depthMm), mInEpidural = true;
    mPrevGood = r;
}

TraineeMetrics TraineeMetricsAccumulator::result() const
{
    TraineeMetrics m = mM;
    m.outcome = mOutcome.result();
    m.success = m.outcome.success;
    if (mInEpidural) m.overshootMm = mEpidural;
    if (mN > 0) {
        m.speedMeanMmPerS = mSum / double(mN);
        m.speedVarianceMm2PerS2 = std::max(0.0, mSum2 / double(mN) - m.speedMeanMmPerS * m.speedMeanMmPerS);
    }
    if (mHaveFirst) m.durationS = mLast.timeS - mFirst.timeS;
    // syrrate ([S19], §2.3): syringe fraction emptied from the derma's puncture to the
    // end, per metre travelled along the path in that time.
    if (std::isfinite(mSkinT) && mHaveFirst && std::isfinite(mLast.plungerFraction)) {
        const double travelM = (mLast.depthMm - mSkinDepth) * 1e-3;
        if (travelM > 0.0) m.syrrate = (mLast.plungerFraction - (mHaveStartFraction ? mStartFraction : 0.0)) / travelM;
    }
    return m;
}

TraineeMetrics traineeMetrics(const Session& s, const std::vector<Layer>& layers, const Vec3d& pathDirection,
    const SuccessCriteria& success, std::optional<Vec3d> target)
{
    // Events and records merged in time order: an event before the records of its tick.
    std::vector<Event> events = s.events;
    std::stable_sort(events.begin(), events.end(), [](const Event& a, const Event& b) { return a.timeS < b.timeS; });
    TraineeMetricsAccumulator acc(layers, pathDirection, success, target);
    std::size_t next = 0;
    for (const ServoRecord& r : s.records) {
        while (next < events.size() && events[next].timeS <= r.timeS) acc.addEvent(events[next++]);
        acc.addRecord(r);
    }
    while (next < events.size()) acc.addEvent(events[next++]);
    return acc.result();
}

SessionRecorder::SessionRecorder(const fs::path& dir, const std::vector<Layer>& layers, const Vec3d& pathDirection,
    const SuccessCriteria& success, std::optional<Vec3d> target)
    : mLayers(layers), mMetrics(layers, pathDirection, success, target)
{
    fs::create_directories(dir);
    mSession = std::make_unique<StreamingOutput>(dir / "session.csv");
    mEventFile = std::make_unique<StreamingOutput>(dir / "events.csv");
    mSession->stream() << std::setprecision(10) << kSessionHeader;
    mEventFile->stream() << std::setprecision(10) << kEventsHeader;
    mPending.reserve(1024);
}

SessionRecorder::~SessionRecorder() = default;

void SessionRecorder::writeEvent(const Event& e)
{
    mMetrics.addEvent(e);
    writeEventRow(mEventFile->stream(), e, mLayers);
    ++mEvents;
}

void SessionRecorder::applyEventsUpTo(double timeS)
{
    while (mPendingHead < mPending.size() && mPending[mPendingHead].timeS <= timeS)
        writeEvent(mPending[mPendingHead++]);
    if (mPendingHead == mPending.size()) mPending.clear(), mPendingHead = 0;
}

void SessionRecorder::addEvent(const Event& e)
{
    // Compact before growing: the pending list holds only events ahead of the records.
    if (mPendingHead > 0 && mPending.size() == mPending.capacity()) {
        mPending.erase(mPending.begin(), mPending.begin() + std::ptrdiff_t(mPendingHead));
        mPendingHead = 0;
    }
    mPending.push_back(e);
}

void SessionRecorder::addRecord(const ServoRecord& r)
{
    applyEventsUpTo(r.timeS);
    mMetrics.addRecord(r);
    writeRecordRow(mSession->stream(), r, mLayers);
    mLast = r;
    ++mRecords;
}

void SessionRecorder::drain(ServoLoop& loop)
{
    ServoRecord r;
    Event e;
    // Records first: an event taken after them belongs to a record already taken or a later one.
    // One batch of records at a time, so that a loop faster than this drain still ends it.
    long batch = 0;
    while (batch < (1L << 16) && loop.popRecord(r)) {
        // Events up to this record may still be queued: take them before the record.
        while (loop.popEvent(e)) addEvent(e);
        addRecord(r);
        ++batch;
    }
    while (loop.popEvent(e)) addEvent(e);
}

TraineeMetrics SessionRecorder::metrics()
{
    TraineeMetricsAccumulator copy = mMetrics;
    for (std::size_t i = mPendingHead; i < mPending.size(); ++i) copy.addEvent(mPending[i]);
    return copy.result();
}

void SessionRecorder::finish(OutputSet& out, long droppedRecords)
{
    applyEventsUpTo(kNoLimit);
    writeSessionTrailer(mSession->stream(), mRecords, droppedRecords);
    mSession->addTo(out);
    mEventFile->addTo(out);
}

} // namespace voxhap::haptic
