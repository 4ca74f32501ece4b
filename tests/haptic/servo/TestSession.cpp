// SPDX-License-Identifier: Apache-2.0
/// @file TestSession.cpp
/// @brief Session files that readSessionPoses refuses (a bad header, a bad line,
/// times that do not increase, fewer than two records), each with one line naming
/// the file and the line; and the servo loop's record queue when nobody drains
/// it: records are dropped and counted, the oldest kept, and the tick goes on.

#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"
#include "haptic/Events.h"
#include "haptic/servo/Session.h"
#include "haptic/servo/SpscQueue.h"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <string>

namespace voxhap::haptic {
namespace {

namespace fs = std::filesystem;

/// The header writeSession writes (Session.h).
const std::string kSessionHeader = "t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z,fx_N,fy_N,fz_N,plunger_N,depth_mm,"
                                   "axial_N,layer,state,fault,critical,plunger_fraction\n";

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

} // namespace
} // namespace voxhap::haptic
