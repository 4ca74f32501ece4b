// SPDX-License-Identifier: Apache-2.0
/// @file ServoLoop.h
/// @brief The haptic servo loop (architecture.md "Threads"): one thread at a fixed
/// rate with absolute deadlines; each tick reads the device, steps the force
/// model and applies the watchdog (ServoStep.h) and writes the force. The tick never allocates,
/// locks, throws or logs: events and records leave through lock-free queues, and
/// timing statistics are lock-free histograms.
#pragma once

#include "haptic/force/NeedleForceModel.h"
#include "haptic/servo/Device.h"
#include "haptic/servo/ServoStep.h"
#include "haptic/servo/ShaftSnapshot.h"
#include "haptic/servo/SpscQueue.h"

#include <array>
#include <atomic>
#include <cstdint>
#include <limits>
#include <memory>
#include <pthread.h>
#include <sched.h>
#include <string>
#include <thread>

namespace voxhap::haptic {

/// @brief Where the real-time loop (ServoLoop::start) reads the time and waits for
/// its deadlines. The default is the monotonic clock; tests set a simulated one to
/// reach the stall watchdog and to count ticks without wall-clock timing. Both calls
/// run on the servo thread: they must not block beyond the deadline, allocate, lock,
/// throw or log.
class ServoClock {
public:
    virtual ~ServoClock() = default;
    /// @brief Monotonic time [ns].
    virtual std::int64_t nowNs() noexcept = 0;
    /// @brief Return at @p deadlineNs (on the nowNs() time line) or later; @p spin asks
    /// for a busy wait instead of a sleep.
    virtual void waitUntilNs(std::int64_t deadlineNs, bool spin) noexcept = 0;
};

/// @brief CLOCK_MONOTONIC, waited for with clock_nanosleep on absolute deadlines or by
/// spinning (the default ServoClock).
ServoClock& monotonicServoClock() noexcept;

struct ServoOptions {
    double rateHz = 1000.0;
    /// Watchdog (physics.md §6.3) [chosen]. Each tick moves the gain on the force by
    /// its period (at least the nominal 1/rateHz) over rampS: down while the device
    /// has been quiet (no valid reading) for longer than watchdogS, which zeroes it
    /// rampS later; down when the period itself lasted longer than watchdogS (a
    /// stalled loop: one step of period/rampS, as if the ramp had run through the
    /// stall, so a stall of rampS or more zeroes it at once); otherwise up, to 1.
    /// A lost device zeroes it at once.
    double watchdogS = 0.020; ///< [s] 20 periods at 1 kHz
    double rampS = 0.050;     ///< [s]
    /// Periods up to this long are waited for by spinning, not sleeping: the kernel's
    /// sleep granularity (tens of µs) is a whole period at 20 kHz and above [s].
    double spinBelowS = 100e-6;
    /// Sleeping loops on the monotonic clock sleep until this long before each
    /// deadline and spin the rest: the kernel wakes a real-time thread tens of µs
    /// late at its 99th percentile on a virtual machine, so the last stretch is
    /// waited for on the CPU (a tenth of a core at 1 kHz). 0: sleep to the deadline [s].
    double wakeLeadS = 100e-6;
    /// Bounded catch-up after a missed deadline [chosen]. The model integrates with
    /// the nominal dt = 1/rateHz on every tick (NeedleInput::dtS), so the tissue's
    /// clock is the tick count times the period: periods dropped after a stall slow
    /// that clock against the hand's. When the loop falls behind by at most this many
    /// periods, the missed ticks run at once, one after another, until the loop is
    /// back on its grid of t0 + n·T; the device holds the last force written, so the
    /// hand feels only the newest of them. A longer stall drops its periods (counted
    /// in skippedPeriods()) and re-anchors the grid. −1 (default): the periods that fit
    /// in watchdogS, so that every gap the watchdog does not treat as a stall (a
    /// virtual machine's host takes the CPU for 1-10 ms at times) is caught up, and
    /// every gap it does treat as one is dropped; 0 drops every missed period.
    int catchUpPeriods = -1;
    /// Spinning loops only (periods up to spinBelowS), on the monotonic clock: before
    /// the first tick, spin 60 ms and find the phase of the period at which the
    /// machine interrupts the thread (InterruptionPhase.h: the kernel's scheduler tick,
    /// 20-30 µs a time on a virtual machine), then start the grid so that each tick
    /// ends interruptionLeadS before it. A gap that lands while the loop waits costs
    /// nothing; one that lands on a tick makes a 50 kHz loop miss its deadline.
    bool alignToInterruptions = true;
    double interruptionLeadS = 3e-6; ///< [s] above the tick's p99 compute (< 1 µs) [chosen]
    /// The clock of the real-time loop; null: monotonicServoClock(). Set before
    /// start(); it must outlive the loop.
    ServoClock* clock = nullptr;
    /// Real-time thread: SCHED_FIFO at realtimePriority and the
    /// process's memory locked (mlockall), when the process may (root,
    /// CAP_SYS_NICE and CAP_IPC_LOCK, or rtprio and memlock limits); otherwise the
    /// loop runs at normal priority and realtimeStatus() says how to grant it.
    /// Off by default (tests and batch runs); serve and bench servo turn it on.
    bool realtime = false;
    int realtimePriority = 80; ///< of 1..99: above interrupt threads (50), below the watchdogs (99) [chosen]
    bool lockMemory = true;    ///< with realtime: mlockall (process-wide, kept after the loop)
    /// Pin the loop to this CPU (-1: no pinning).
    int pinCpu = -1;
    /// The scheduler call (tests replace it to see the request and to refuse it);
    /// null: pthread_setschedparam.
    int (*setScheduler)(pthread_t, int, const sched_param*) = nullptr;
};

/// @brief What the loop got of what ServoOptions::realtime asked for.
struct RealtimeStatus {
    bool requested = false;
    bool scheduled = false; ///< SCHED_FIFO granted
    bool memoryLocked = false;
    bool pinned = false;
    int priority = 0; ///< the priority asked for
    std::string why;  ///< one line when something was refused: what and how to grant it
};

/// @brief One tick, for the session record.
struct ServoRecord {
    double timeS = 0;
    Vec3d tip{0, 0, 0}, direction{0, 0, 1}, force{0, 0, 0};
    double plungerN = 0, depthMm = 0, axialN = 0;
    double plungerFraction = std::numeric_limits<double>::quiet_NaN(); ///< syringe emptied, 0..1 (DeviceReading)
    double rollRad = std::numeric_limits<double>::quiet_NaN(); ///< the needle's roll (DeviceReading); NaN: none sensed
    std::int16_t layer = -1;
    LayerState state = LayerState::Intact;
    bool fault = false, critical = false;
};

/// @brief Lock-free timing statistics: compute time per tick and period error.
class TickStats {
public:
    static constexpr int kBins = 4096; ///< compute: 25 ns bins up to 102 µs; period: 1 µs bins
    void addCompute(double ns) noexcept { add(mCompute, ns / 25.0); }
    void addPeriodError(double ns) noexcept { add(mJitter, ns / 1000.0); }
    /// @brief Quantile @p q of the compute time [ns] (upper edge of its bin).
    double computeQuantileNs(double q) const noexcept { return quantile(mCompute, q) * 25.0; }
    double jitterQuantileNs(double q) const noexcept { return quantile(mJitter, q) * 1000.0; }
    long count() const noexcept;

private:
    using Hist = std::array<std::atomic<std::uint32_t>, kBins + 1>;
    static void add(Hist& h, double bin) noexcept;
    static double quantile(const Hist& h, double q) noexcept;
    Hist mCompute{}, mJitter{};
};

class ServoLoop {
public:
    ServoLoop(NeedleForceModel& model, Device& device, const ServoOptions& options = {});
    ~ServoLoop();
    ServoLoop(const ServoLoop&) = delete;
    ServoLoop& operator=(const ServoLoop&) = delete;

    /// @brief Run on its own thread in real time until stop() or the device finishes.
    void start();
    /// @brief Stop at once (the device keeps the last force it was sent: use
    /// releaseAndStop() when a hand may be on it).
    void stop();
    /// @brief Ramp the force down to zero at the watchdog's rate (1/rampS per
    /// second: 50 ms from full force), send one zero force, then stop. What a
    /// Ctrl-C or SIGTERM does before anything is written (physics.md §6.3).
    /// Without a running thread the ramp happens on the next runTicks().
    void releaseAndStop();
    /// @brief Ask for the ramp to zero without waiting (runTicks() then ends
    /// once a zero force was sent).
    void beginRelease() noexcept { mStep.beginRelease(); }
    /// @brief The zero force that ends a release has been sent.
    bool released() const noexcept { return mStep.released(); }
    bool running() const noexcept { return mRunning.load(); }
    /// @brief After start(): what real-time scheduling the loop thread got.
    const RealtimeStatus& realtimeStatus() const noexcept { return mRealtime; }
    /// @brief Run @p ticks ticks now on the caller's thread, in simulated time (tests).
    void runTicks(long ticks) noexcept;

    // Consumer side (another thread).
    bool popEvent(Event& e) noexcept { return mEvents->pop(e); }
    bool popRecord(ServoRecord& r) noexcept { return mRecords->pop(r); }
    long droppedRecords() const noexcept { return mRecords->dropped(); }
    long droppedEvents() const noexcept { return mEvents->dropped(); }
    const TickStats& stats() const noexcept { return mStats; }
    long ticks() const noexcept { return mTicks.load(); }
    /// @brief Time from the first tick to the last of start()'s thread [s]: the
    /// window the loop's rate is measured over, without the set-up before the
    /// first tick (mlockall, the scheduler call, the thread's start).
    double tickingSeconds() const noexcept
    {
        return double(mLastTickNs.load(std::memory_order_relaxed) - mFirstTickNs.load(std::memory_order_relaxed)) *
            1e-9;
    }
    /// @brief Times the loop fell behind its grid (a tick ended after the next
    /// deadline), once per episode: the ticks that catch up are not counted again.
    long overruns() const noexcept { return mOverruns.load(); }
    /// @brief The interruption phase the grid was aligned to [ns into the period], or
    /// −1 when the loop did not align (sleeping loop, option off, no dominant phase).
    std::int64_t interruptionPhaseNs() const noexcept { return mInterruptionPhase.load(); }
    /// @brief Periods dropped, not caught up, after stalls longer than
    /// ServoOptions::catchUpPeriods.
    long skippedPeriods() const noexcept { return mSkipped.load(); }
    double maxComputeNs() const noexcept { return mMaxComputeNs.load(); }
    /// @brief The last rendered force magnitude [N] and layer, for a status line.
    double lastForceN() const noexcept { return mLastForce.load(); }
    int lastLayer() const noexcept { return mLastLayer.load(); }
    double watchdogGain() const noexcept { return mGainPublic.load(); }
    /// @brief A bending needle's shaft, published by the first tick and then every
    /// kShaftPublishS of the loop's time (a display rate); empty when the needle
    /// does not bend. For a viewer (`serve --viewer`), never for control.
    const ShaftSnapshot& shaft() const noexcept { return mShaft; }
    static constexpr double kShaftPublishS = 0.010; ///< [chosen]: 100 Hz, above the viewer's 50 Hz

private:
    void tick(double timeS, double dtS, double lastPeriodS) noexcept;
    void loop() noexcept;

    NeedleForceModel& mModel;
    Device& mDevice;
    ServoOptions mOpt;
    ServoClock* mClock;
    ServoStep mStep; ///< the model's step and the watchdog
    TickStats mStats;
    // On the heap: 65 s of records at 1 kHz is megabytes, too big for a stack.
    std::unique_ptr<SpscQueue<Event, 1024>> mEvents;
    std::unique_ptr<SpscQueue<ServoRecord, 1 << 16>> mRecords;
    std::atomic<bool> mRunning{false}, mStop{false};
    RealtimeStatus mRealtime;
    std::atomic<int> mSchedError{-1}; ///< set by the loop thread: 0 granted, else errno
    std::atomic<long> mTicks{0}, mOverruns{0}, mSkipped{0};
    std::atomic<std::int64_t> mFirstTickNs{0}, mLastTickNs{0},
        mInterruptionPhase{-1}; ///< on the loop clock's time line
    std::atomic<double> mMaxComputeNs{0}, mLastForce{0}, mGainPublic{1};
    std::atomic<int> mLastLayer{-1};
    double mSimTime = 0.0;
    ShaftSnapshot mShaft;
    long mShaftEveryTicks = 1; ///< kShaftPublishS in ticks at the loop's rate
    std::thread mThread;
};

} // namespace voxhap::haptic
