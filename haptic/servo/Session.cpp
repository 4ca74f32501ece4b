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
#include <limits>
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
    "fault,critical,plunger_fraction,roll_deg\n";
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
      << r.plungerFraction << ',' << r.rollRad * (180.0 / kPi) << '\n';
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

/// The index of column @p name in the header @p header, or −1.
int columnOf(const std::string& header, const std::string& name)
{
    std::istringstream h(header);
    std::string column;
    for (int i = 0; std::getline(h, column, ','); ++i) {
        if (!column.empty() && column.back() == '\r') column.pop_back();
        if (column == name) return i;
    }
    return -1;
}

/// Field @p i of the CSV line @p line (empty when the line is shorter).
std::string field(const std::string& line, int i)
{
    std::istringstream l(line);
    std::string f;
    for (int k = 0; k <= i; ++k) {
        if (!std::getline(l, f, ',')) return {};
    }
    if (!f.empty() && f.back() == '\r') f.pop_back();
    return f;
}

/// A roll in degrees: a finite number, or nan or nothing (the device senses none).
bool parseRollDeg(const std::string& text, double& deg)
{
    if (text.empty() || text == "nan" || text == "NaN" || text == "-nan") {
        deg = std::numeric_limits<double>::quiet_NaN();
        return true;
    }
    std::istringstream t(text);
    return (t >> deg) && std::isfinite(deg) && (t >> std::ws).eof();
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
    // The roll, where the file has it (sessions written before it have no column):
    // NaN, a device that senses none, or degrees.
    const int rollColumn = columnOf(line, "roll_deg");
    std::vector<ServoRecord> out;
    int last = 1; // the last line read
    for (int n = 2; std::getline(in, line); ++n) {
        if (line.rfind('#', 0) == 0) continue; // a comment (the closing line states the counts)
        last = n;
        double rollDeg = std::numeric_limits<double>::quiet_NaN();
        if (rollColumn >= 0 && !parseRollDeg(field(line, rollColumn), rollDeg))
            throw ValueError(file.string() + ": line " + std::to_string(n) + ": bad roll_deg (degrees, or nan)");
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
        r.rollRad = degToRad(rollDeg);
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
