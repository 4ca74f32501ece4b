// SPDX-License-Identifier: Apache-2.0
/// @file TestSession.cpp
/// @brief Session files that readSessionPoses refuses (a bad header, a bad line,
/// times that do not increase, fewer than two records), each with one line naming
/// the file and the line; the servo loop's record queue when nobody drains
/// it: records are dropped and counted, the oldest kept, and the tick goes on;
/// and the streaming SessionRecorder: the files grow under temporary names,
/// replace an earlier session only at the commit, and state the dropped count.

#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "haptic/Events.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/servo/Session.h"
#include "haptic/servo/SpscQueue.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

namespace voxhap::haptic {
namespace {

namespace fs = std::filesystem;

/// The header writeSession writes (Session.h).
const std::string kSessionHeader = "t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z,fx_N,fy_N,fz_N,plunger_N,depth_mm,"
                                   "axial_N,layer,state,fault,critical,plunger_fraction,roll_deg\n";

class SessionFile : public test::TempDirTest {
protected:
    fs::path write(const std::string& name, const std::string& text) const
    {
        const fs::path p = mDir / name;
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
    /// readSessionPoses(@p text) throws a ValueError of one line naming the file and
    /// containing @p what (the line number and the reason).
    void expectRefused(const std::string& name, const std::string& text, const std::string& what) const
    {
        test::expectRefused<ValueError>([](const fs::path& f) { readSessionPoses(f); }, write(name, text), what);
    }
};

// The positive control: the same reader accepts a good file, with the pose columns
// exactly as written (the decimal text parses to the same doubles as the literals)
// and the columns after dir_z ignored.
TEST_F(SessionFile, ReadsThePoseColumns)
{
    const fs::path p = write("good.csv",
        kSessionHeader + "0,1.5,-2.25,3,0,0,1,0.1,0.2,0.3,0,0,0,fat,intact,0,0,nan\n" +
            "0.001,1.5,-2.5,3.125,0,-0.6,0.8,0,0,0,0,0.25,0,,outside,0,0,nan\n");
    const std::vector<ServoRecord> r = readSessionPoses(p);
    ASSERT_EQ(r.size(), 2u);
    EXPECT_EQ(r[0].timeS, 0.0);
    EXPECT_EQ(r[0].tip, Vec3d(1.5, -2.25, 3.0));
    EXPECT_EQ(r[0].direction, Vec3d(0.0, 0.0, 1.0));
    EXPECT_EQ(r[1].timeS, 0.001);
    EXPECT_EQ(r[1].tip, Vec3d(1.5, -2.5, 3.125));
    EXPECT_EQ(r[1].direction, Vec3d(0.0, -0.6, 0.8));
}

// A session written before the roll was recorded (no roll_deg column) reads as a
// device without one; a roll that is not a number is refused with its line.
TEST_F(SessionFile, TheRollColumnIsOptionalAndChecked)
{
    const std::string old = "t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z,fx_N,fy_N,fz_N,plunger_N,depth_mm,"
                            "axial_N,layer,state,fault,critical,plunger_fraction\n";
    const std::vector<ServoRecord> r = readSessionPoses(write("old.csv", old + "0,0,0,0,0,0,1\n0.001,0,0,1,0,0,1\n"));
    ASSERT_EQ(r.size(), 2u);
    EXPECT_TRUE(std::isnan(r[0].rollRad) && std::isnan(r[1].rollRad));
    const std::string rows = "0,0,0,0,0,0,1,0,0,0,0,0,0,,outside,0,0,nan,";
    const std::vector<ServoRecord> turned = readSessionPoses(write("turned.csv",
        kSessionHeader + rows +
            "nan\n0.001,0,0,1,0,0,1,0,0,0,0,0,0,,outside,"
            "0,0,nan,-90\n"));
    EXPECT_TRUE(std::isnan(turned[0].rollRad));
    EXPECT_EQ(turned[1].rollRad, degToRad(-90.0));
    expectRefused("word.csv", kSessionHeader + rows + "nan\n0.001,0,0,1,0,0,1,0,0,0,0,0,0,,outside,0,0,nan,left\n",
        "line 3: bad roll_deg");
    expectRefused("inf.csv", kSessionHeader + rows + "1e999\n0.001,0,0,1,0,0,1\n", "line 2: bad roll_deg");
}

TEST_F(SessionFile, MissingFileIsRefusedNamingIt)
{
    test::expectRefused<IoError>([](const fs::path& f) { readSessionPoses(f); }, mDir / "absent.csv", "cannot open");
}

TEST_F(SessionFile, DeviceOrFifoIsRefusedUnopened)
{
    // /dev/zero never ends and a FIFO without a writer never answers: both are
    // refused from the path alone, in one line naming the file.
    test::expectRefused<IoError>([](const fs::path& f) { readSessionPoses(f); }, fs::path("/dev/zero"), "file type");
}

TEST_F(SessionFile, BadHeaderIsRefusedAtLineOne)
{
    const std::string rows = "0,0,0,0,0,0,1\n0.001,0,0,1,0,0,1\n";
    expectRefused("other.csv", "time,x,y,z,dx,dy,dz\n" + rows, "line 1: not a voxhap session");
    expectRefused("headless.csv", rows, "line 1: not a voxhap session"); // the first record is no header
    expectRefused("empty.csv", "", "line 1: not a voxhap session");
}

TEST_F(SessionFile, BadLineIsRefusedWithItsNumber)
{
    const std::string good = kSessionHeader + "0,0,0,0,0,0,1\n";
    expectRefused("word.csv", good + "0.001,1,abc,3,0,0,1\n", "line 3: bad time, tip or direction");
    expectRefused("short.csv", good + "0.001,1,2,3,0,0\n", "line 3: bad time, tip or direction"); // six fields
    expectRefused("overflow.csv", good + "0.001,1,2,3,0,0,1\n0.002,1e999,2,3,0,0,1\n",
        "line 4: bad time, tip or direction"); // not a finite double
    expectRefused("blank.csv", good + "\n0.001,1,2,3,0,0,1\n", "line 3: bad time, tip or direction");
}

TEST_F(SessionFile, TimesThatDoNotIncreaseAreRefusedWithTheLine)
{
    const std::string start = kSessionHeader + "0,0,0,0,0,0,1\n0.001,0,0,1,0,0,1\n";
    expectRefused("repeated.csv", start + "0.001,0,0,2,0,0,1\n", "line 4: t_s must increase");
    expectRefused("backwards.csv", start + "0.0005,0,0,2,0,0,1\n", "line 4: t_s must increase");
}

TEST_F(SessionFile, FewerThanTwoRecordsAreRefusedWithTheLastLine)
{
    expectRefused("header-only.csv", kSessionHeader, "line 1: the file ends after 0 record(s)");
    expectRefused("one.csv", kSessionHeader + "0,0,0,0,0,0,1\n", "line 2: the file ends after 1 record(s)");
}

// A bounded queue that is full refuses the push at once, counts it, and keeps what
// it holds: the oldest items, in order. Draining makes room again (the ring wraps).
// What writeSession writes, readSessionPoses reads back: times exactly, even two
// that agree to 15 digits (at 10 digits they merged and the reader refused the
// file it had just been given).
TEST_F(SessionFile, WrittenTimesReadBackExactly)
{
    Session s;
    for (const double t : {0.0, 0.002999999999999999, 0.003, 1234.5678901234567}) {
        ServoRecord r;
        r.timeS = t;
        r.tip = Vec3d(1.0, 2.0, 3.0);
        r.direction = Vec3d(0.0, 0.0, 1.0);
        s.records.push_back(r);
    }
    writeSession(s, {}, mDir / "written");
    const std::vector<ServoRecord> back = readSessionPoses(mDir / "written" / "session.csv");
    ASSERT_EQ(back.size(), s.records.size());
    for (std::size_t i = 0; i < back.size(); ++i) EXPECT_EQ(back[i].timeS, s.records[i].timeS) << "record " << i;
}

// Poses no hand on the device makes (a tip 1e6 mm away, a NaN, a 50 mm jump in
// one millisecond) are counted as faults and left out: the mean speed is that of
// the steady 10 mm/s advance around them, not hundreds of metres per second.
TEST(TraineeMetricsFaults, PosesOutsideTheWorkspaceAreFaultsNotSamples)
{
    Session s;
    for (int i = 0; i <= 1000; ++i) {
        ServoRecord r;
        r.timeS = 0.001 * i;
        r.depthMm = 0.01 * i; // 10 mm/s
        r.tip = Vec3d(0.0, 0.0, r.depthMm);
        r.direction = Vec3d(0.0, 0.0, 1.0);
        if (i == 300) r.tip = Vec3d(1e6, 0.0, 0.0), r.depthMm = 1e6;
        if (i == 500) r.tip.x() = std::numeric_limits<double>::quiet_NaN();
        if (i == 700) r.tip.z() += 50.0, r.depthMm += 50.0;
        s.records.push_back(r);
    }
    s.events.push_back({EventType::SkinEntry, 0.0, 0.0, 0});
    const TraineeMetrics m = traineeMetrics(s, {}, Vec3d(0, 0, 1));
    EXPECT_EQ(m.poseFaults, 3);
    // Every good step advances 0.01 mm per ms (two across each skipped record):
    // 10 mm/s exactly, up to the round-off of the decimal times.
    constexpr double kSpeedRoundOff = 1e-6; // mm/s: times and depths of 1e-3 and 1e-2 steps in double
    EXPECT_NEAR(m.speedMeanMmPerS, 10.0, kSpeedRoundOff);
    EXPECT_LT(m.speedVarianceMm2PerS2, kSpeedRoundOff);
}

TEST(RecordQueue, FullQueueDropsCountsAndKeepsTheOldest)
{
    SpscQueue<int, 4> q;
    for (int i = 1; i <= 6; ++i) EXPECT_EQ(q.push(i), i <= 4) << i;
    EXPECT_EQ(q.dropped(), 2);
    int v = 0;
    for (int i = 1; i <= 4; ++i) {
        ASSERT_TRUE(q.pop(v));
        EXPECT_EQ(v, i);
    }
    EXPECT_FALSE(q.pop(v));
    for (int i = 7; i <= 10; ++i) EXPECT_TRUE(q.push(i)) << i;
    EXPECT_FALSE(q.push(11));
    EXPECT_EQ(q.dropped(), 3);
    for (int i = 7; i <= 10; ++i) {
        ASSERT_TRUE(q.pop(v));
        EXPECT_EQ(v, i);
    }
}

/// A device held still in the air before the skin: valid readings, never finished.
class HeldStillDevice final : public Device {
public:
    HeldStillDevice(const Vec3d& tip, const Vec3d& dir, const DeviceLimits& limits) : mLimits(limits)
    {
        mReading.tip = tip;
        mReading.direction = dir;
        mReading.valid = true;
    }
    DeviceReading read(double) noexcept override { return mReading; }
    void write(const Vec3d&, double, double) noexcept override { }
    const DeviceLimits& limits() const noexcept override { return mLimits; }
    std::string name() const override { return "still"; }

private:
    DeviceReading mReading;
    DeviceLimits mLimits;
};

/// Simulated time is a running sum of 1 ms periods: after 7·10⁴ of them its
/// round-off is ~1e-9 s. A microsecond is far above that and far below a period,
/// so it still tells every tick from its neighbours.
constexpr double kSimTimeTolS = 1e-6;

// The servo loop's record queue holds 2^16 records (65 s at 1 kHz, ServoLoop.h).
// Ticks driven directly, nobody draining: every tick still runs, the records past
// the capacity are dropped and counted, the ones kept are the first, without a
// gap; once drained, records flow again and the count stays.
TEST(RecordQueue, ServoLoopDropsAndCountsRecordsNobodyDrains)
{
    static const SceneInstance inst(loadScene("senac-average"), nullptr, volume::TissueTable::builtin());
    auto model = inst.makeModel();
    const Vec3d dir = (inst.target() - inst.entry()).normalized();
    HeldStillDevice device(inst.entry() - 20.0 * dir, dir, model->device());
    ServoOptions opt;
    opt.rateHz = 1000.0;
    ServoLoop loop(*model, device, opt);
    constexpr long kCapacity = 1L << 16, kExtra = 1000;

    loop.runTicks(kCapacity + kExtra);
    EXPECT_EQ(loop.ticks(), kCapacity + kExtra); // a full queue does not stop or block the tick
    EXPECT_EQ(loop.droppedRecords(), kExtra);

    ServoRecord r;
    long kept = 0, outOfPlace = 0;
    while (loop.popRecord(r)) {
        if (!(std::abs(r.timeS - double(kept) * 1e-3) <= kSimTimeTolS)) ++outOfPlace;
        ++kept;
    }
    EXPECT_EQ(kept, kCapacity);
    EXPECT_EQ(outOfPlace, 0) << "the records kept are ticks 0 to " << kCapacity - 1 << " in order";

    loop.runTicks(10);
    EXPECT_EQ(loop.droppedRecords(), kExtra);
    for (long n = kCapacity + kExtra; n < kCapacity + kExtra + 10; ++n) {
        ASSERT_TRUE(loop.popRecord(r)) << n;
        EXPECT_NEAR(r.timeS, double(n) * 1e-3, kSimTimeTolS);
    }
    EXPECT_FALSE(loop.popRecord(r));
}

/// Lines of @p file: data rows (not the header, not comments) and the comment lines.
struct CsvLines {
    std::vector<std::string> rows, comments;
};
CsvLines readCsv(const fs::path& file)
{
    CsvLines out;
    std::ifstream in(file);
    std::string line;
    std::getline(in, line); // header
    while (std::getline(in, line)) (line.rfind('#', 0) == 0 ? out.comments : out.rows).push_back(line);
    return out;
}

// A whole session through the recorder, drained the way serve drains it (every
// 100 ticks) from a loop whose record queue overflowed once: session.csv holds
// exactly the records the loop kept, in order, its closing line states the 1 000
// dropped, the reader accepts it, and events.csv holds the events in time order.
// Until the commit, an earlier session in the folder is untouched.
TEST_F(SessionFile, RecorderStreamsTheSessionAndStatesTheDroppedCount)
{
    static const SceneInstance inst(loadScene("senac-average"), nullptr, volume::TissueTable::builtin());
    auto model = inst.makeModel();
    const Vec3d dir = (inst.target() - inst.entry()).normalized();
    HeldStillDevice device(inst.entry() - 20.0 * dir, dir, model->device());
    ServoLoop loop(*model, device, ServoOptions{});
    const fs::path out = mDir / "serve";
    fs::create_directories(out);
    std::ofstream(out / "session.csv") << "an earlier session\n";

    constexpr long kCapacity = 1L << 16, kExtra = 1000, kAfter = 500;
    {
        SessionRecorder rec(out, model->layers(), dir);
        loop.runTicks(kCapacity + kExtra); // nobody drains: the last 1 000 are dropped
        rec.drain(loop);
        for (long i = 0; i < kAfter; i += 100) loop.runTicks(100), rec.drain(loop);
        EXPECT_EQ(rec.recordCount(), kCapacity + kAfter);
        std::string earlier;
        std::getline(std::ifstream(out / "session.csv"), earlier);
        EXPECT_EQ(earlier, "an earlier session") << "replaced before the commit";

        OutputSet set;
        rec.finish(set, loop.droppedRecords());
        set.commit();
    }
    const CsvLines session = readCsv(out / "session.csv");
    ASSERT_EQ(long(session.rows.size()), kCapacity + kAfter);
    ASSERT_EQ(session.comments.size(), 1u);
    EXPECT_EQ(session.comments[0].rfind("# 66036 records written, 1000 dropped", 0), 0u) << session.comments[0];
    const std::vector<ServoRecord> poses = readSessionPoses(out / "session.csv");
    ASSERT_EQ(long(poses.size()), kCapacity + kAfter);
    EXPECT_NEAR(poses[kCapacity - 1].timeS, double(kCapacity - 1) * 1e-3, kSimTimeTolS);
    // After the gap the next record is the first tick run after the drain.
    EXPECT_NEAR(poses[kCapacity].timeS, double(kCapacity + kExtra) * 1e-3, kSimTimeTolS);
    for (const auto& e : fs::directory_iterator(out))
        EXPECT_EQ(e.path().filename().string().rfind(".tmp.", 0), std::string::npos) << e.path();
}

// Events are written in time order, each before the records of its tick, and the
// metrics see them in that order even when a drain takes an event ahead of its
// record: a skin entry at 0.5 s makes only the later advance count in the speed.
TEST_F(SessionFile, RecorderOrdersEventsBeforeTheRecordsOfTheirTick)
{
    const fs::path out = mDir / "ordered";
    SessionRecorder rec(out, {}, Vec3d(0, 0, 1));
    // Depth 0 until 0.5 s, then 20 mm/s: the mean advancing speed after the skin is 20 mm/s.
    rec.addEvent({EventType::SkinEntry, 0.5, 0.0, 0}); // taken ahead of its record
    for (int i = 0; i <= 1000; ++i) {
        ServoRecord r;
        r.timeS = 1e-3 * i;
        r.depthMm = i <= 500 ? 0.0 : 0.02 * (i - 500);
        r.tip = Vec3d(0, 0, r.depthMm);
        rec.addRecord(r);
        if (i == 750) rec.addEvent({EventType::Pop, 0.75, 5.0, 0}); // after its record (never earlier)
    }
    const TraineeMetrics m = rec.metrics();
    constexpr double kSpeedRoundOff = 1e-6; // mm/s: decimal times and depths in double
    EXPECT_NEAR(m.speedMeanMmPerS, 20.0, kSpeedRoundOff);
    EXPECT_EQ(m.pops, 1);
    OutputSet set;
    rec.finish(set, 0);
    set.commit();
    const CsvLines events = readCsv(out / "events.csv");
    ASSERT_EQ(events.rows.size(), 2u);
    EXPECT_EQ(events.rows[0].rfind("0.5,0,skin_entry", 0), 0u) << events.rows[0];
    EXPECT_EQ(events.rows[1].rfind("0.75,5,pop", 0), 0u) << events.rows[1];
}

// A recorder dropped without a commit (an exception in serve, a failed write)
// leaves no temporary and no session behind.
TEST_F(SessionFile, RecorderWithoutCommitLeavesNothing)
{
    const fs::path out = mDir / "abandoned";
    {
        SessionRecorder rec(out, {}, Vec3d(0, 0, 1));
        ServoRecord r;
        rec.addRecord(r);
        OutputSet unused;
        rec.finish(unused, 0); // handed over, but the set is never committed
    }
    EXPECT_TRUE(fs::is_empty(out));
}

} // namespace
} // namespace voxhap::haptic
