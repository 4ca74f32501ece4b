// SPDX-License-Identifier: Apache-2.0
/// @file TestSessionMemory.cpp
/// @brief A session's memory does not grow with its length (issue 20 item 7):
/// once running, the recorder writes every record and event to disk and into
/// the metrics without a single heap allocation (AllocationCounter.h), so an
/// hour at 100 kHz takes what a second takes.

#include "common/BuiltinTable.h"
#include "stress/AllocationCounter.h"

#include "core/AtomicFile.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/Session.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <unistd.h>

namespace voxhap::haptic {
namespace {

namespace fs = std::filesystem;

TEST(SessionMemory, RecordingAllocatesNothingPerRecordOrEvent)
{
    const fs::path dir = fs::temp_directory_path() / ("voxhap-session-memory-" + std::to_string(::getpid()));
    fs::remove_all(dir);
    {
        // The lumbar-puncture scene's layers: names longer than a short-string buffer
        // ("ligamentum_flavum"), so a copied name per row would allocate.
        const SceneInstance inst(loadScene("lumbar-puncture"), nullptr, test::table());
        auto model = inst.makeModel();
        const auto& layers = model->layers();
        SessionRecorder rec(dir, layers, Vec3d(0, 0, 1));
        const auto feed = [&](long from, long to) {
            for (long i = from; i < to; ++i) {
                ServoRecord r;
                r.timeS = 1e-5 * double(i); // 100 kHz
                r.depthMm = 1e-4 * double(i);
                r.tip = Vec3d(0.1, -0.2, r.depthMm);
                r.force = Vec3d(0.01, 0.02, -1.5);
                r.layer = std::int16_t(i % long(layers.size()));
                if (i % 1000 == 0) rec.addEvent({EventType::Pop, r.timeS, r.depthMm, int(r.layer)});
                rec.addRecord(r);
            }
        };
        feed(0, 2000); // warm-up: the streams' buffers, the locale's facets
        const long before = test::allocations();
        constexpr long kRecords = 300000; // 3 s at 100 kHz, 5 min at 1 kHz
        feed(2000, 2000 + kRecords);
        EXPECT_EQ(test::allocations() - before, 0) << "allocations while recording " << kRecords << " records";
        EXPECT_EQ(rec.recordCount(), 2000 + kRecords);
        OutputSet set;
        rec.finish(set, 0);
        set.commit();
        EXPECT_GT(fs::file_size(dir / "session.csv"), std::uintmax_t(kRecords) * 50); // every row is on disk
    }
    fs::remove_all(dir);
}

} // namespace
} // namespace voxhap::haptic
