// SPDX-License-Identifier: Apache-2.0
/// @file TestForceTrace.cpp
/// @brief Recordings read back for the force–depth plot: columns found by
/// name, |F| from its components, layer bands from where the tip was, events
/// merged by depth, and refusals naming the file, the line and the column.

#include "common/TempDirTest.h"

#include "core/Errors.h"
#include "render/plots/ForceTrace.h"

#include <fstream>

namespace voxhap::render {
namespace {

class Recordings : public test::TempDirTest {
protected:
    void write(const std::string& name, const std::string& text) const { std::ofstream(mDir / name) << text; }
};

TEST_F(Recordings, SessionWithEventsBeside)
{
    // Pulled back once in the fat, then on into the muscle.
    write("session.csv",
        "t_s,tip_x_mm,tip_y_mm,tip_z_mm,dir_x,dir_y,dir_z,fx_N,fy_N,fz_N,plunger_N,depth_mm,axial_N,layer,state,fault,"
        "critical,plunger_fraction\n"
        "0.0,0,1,0,0,-1,0,0,0,0,0,-1,0,,outside,0,0,nan\n"
        "0.1,0,-1,0,0,-1,0,0,3,4,0.5,1,2,skin,punctured,0,0,nan\n"
        "0.2,0,-3,0,0,-1,0,0,0,0,0,3,1,fat,punctured,0,0,nan\n"
        "0.3,0,-5,0,0,-1,0,0,0,0,0,5,1,fat,punctured,0,0,nan\n"
        "0.4,0,-4,0,0,-1,0,0,0,0,0,4,1,fat,punctured,0,0,nan\n"
        "0.5,0,-7,0,0,-1,0,0,0,0,0,7,1,fat,punctured,0,0,nan\n"
        "0.6,0,-9,0,0,-1,0,0,0,0,0,9,1,muscle,punctured,0,0,nan\n"
        "# 7 records written, 0 dropped (the servo loop's record queue was full; the tick went on)\n");
    write("events.csv",
        "t_s,depth_mm,event,layer\n0.05,0,skin_contact,skin\n0.1,1,pop,skin\n0.1,1,skin_entry,skin\n"
        "0.6,9,pop,muscle\n");
    const ForceTrace t = readForceTrace(mDir);
    ASSERT_EQ(t.samples.size(), 7u);
    EXPECT_DOUBLE_EQ(t.samples[1].renderedN, 5.0); // |(0, 3, 4)|
    EXPECT_DOUBLE_EQ(t.samples[1].axialN, 2.0);
    EXPECT_DOUBLE_EQ(t.samples[1].plungerN, 0.5);
    ASSERT_EQ(t.layers.size(), 3u);
    EXPECT_EQ(t.layers[1].name, "fat");
    EXPECT_DOUBLE_EQ(t.layers[1].startMm, 3.0);
    EXPECT_DOUBLE_EQ(t.layers[1].endMm, 7.0); // one band although met twice
    ASSERT_EQ(t.events.size(), 2u);           // skin contact left out, two at 1 mm merged
    EXPECT_EQ(t.events[0].text, "pop, skin_entry");
    EXPECT_DOUBLE_EQ(t.events[1].depthMm, 9.0);
}

TEST_F(Recordings, InsertionCsvEventsPerRow)
{
    write("insertion.csv",
        "t_s,depth_mm,speed_mm_per_s,fx_N,fy_N,fz_N,force_N,axial_model_N,plunger_N,state,layer,events\n"
        "0,-1,2,0,0,0,0,0,0,outside,,\n"
        "1,2,2,0,1.5,0,1.5,1.6,0,punctured,skin,pop;skin_entry\n"
        "2,4,2,0,2,0,2,2.1,0,punctured,fat,\n");
    const ForceTrace t = readForceTrace(mDir / "insertion.csv");
    ASSERT_EQ(t.samples.size(), 3u);
    EXPECT_DOUBLE_EQ(t.samples[2].renderedN, 2.0);
    EXPECT_DOUBLE_EQ(t.samples[2].axialN, 2.1);
    ASSERT_EQ(t.layers.size(), 2u);
    ASSERT_EQ(t.events.size(), 1u);
    EXPECT_EQ(t.events[0].text, "pop, skin_entry");
}

TEST_F(Recordings, RefusedWithFileLineAndColumn)
{
    write("a.csv",
        "t_s,depth_mm,speed_mm_per_s,fx_N,fy_N,fz_N,force_N,axial_model_N,plunger_N,state,layer,events\n"
        "0,oops,2,0,0,0,0,0,0,outside,,\n");
    test::expectRefused<ValueError>([](const auto& p) { readForceTrace(p); }, mDir / "a.csv", "line 2: depth_mm");
    write("b.csv", "t_s,depth_mm\n0,1\n");
    test::expectRefused<ValueError>([](const auto& p) { readForceTrace(p); }, mDir / "b.csv", "neither");
    write("c.csv",
        "t_s,depth_mm,speed_mm_per_s,fx_N,fy_N,fz_N,force_N,axial_model_N,plunger_N,state,layer,events\n0,1\n");
    test::expectRefused<ValueError>([](const auto& p) { readForceTrace(p); }, mDir / "c.csv", "line 2: 2 fields");
    test::expectRefused<IoError>([](const auto& p) { readForceTrace(p); }, mDir / "absent.csv", "cannot open");
    // A FIFO or a device never ends: refused from the path; a line without end is refused at 64 KiB.
    test::expectRefused<IoError>(
        [](const auto& p) { readForceTrace(p); }, std::filesystem::path("/dev/zero"), "file type");
    write("d.csv",
        "t_s,depth_mm,speed_mm_per_s,fx_N,fy_N,fz_N,force_N,axial_model_N,plunger_N,state,layer,events\n" +
            std::string(100000, '1'));
    test::expectRefused<ValueError>(
        [](const auto& p) { readForceTrace(p); }, mDir / "d.csv", "line 2: longer than 65536");
}

} // namespace
} // namespace voxhap::render
