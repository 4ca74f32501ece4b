// SPDX-License-Identifier: Apache-2.0
/// @file ServoLoop.cpp
#include "haptic/servo/ServoLoop.h"

#include "haptic/servo/InterruptionPhase.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <sys/mman.h>
#include <sys/prctl.h>

namespace voxhap::haptic {

void TickStats::add(Hist& h, double bin) noexcept
{
    const int b = std::isfinite(bin) && bin > 0.0 ? int(std::min(bin, double(kBins))) : 0;
    h[std::size_t(b)].fetch_add(1, std::memory_order_relaxed);
}

double TickStats::quantile(const Hist& h, double q) noexcept
{
    std::uint64_t total = 0;
    for (const auto& c : h) total += c.load(std::memory_order_relaxed);
    if (total == 0) return 0.0;
    const double want = std::clamp(q, 0.0, 1.0) * double(total);
    std::uint64_t seen = 0;
    for (int b = 0; b <= kBins; ++b) {
        seen += h[std::size_t(b)].load(std::memory_order_relaxed);
        if (double(seen) >= want) return double(b + 1);
    }
    return double(kBins + 1);
}

long TickStats::count() const noexcept
{
    long n = 0;
    for (const auto& c : mCompute) n += long(c.load(std::memory_order_relaxed));
    return n;
}

namespace {

timespec toTimespec(std::int64_t ns) { return timespec{time_t(ns / 1000000000), long(ns % 1000000000)}; }

class MonotonicServoClock final : public ServoClock {
public:
    std::int64_t nowNs() noexcept override
    {
        timespec ts{};
        clock_gettime(CLOCK_MONOTONIC, &ts);
        return std::int64_t(ts.tv_sec) * 1000000000 + ts.tv_nsec;
    }
    void waitUntilNs(std::int64_t deadlineNs, bool spin) noexcept override
    {
        if (spin) {
            while (nowNs() < deadlineNs) { }
            return;
        }
        const timespec ts = toTimespec(deadlineNs);
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
    }
};

} // namespace

ServoClock& monotonicServoClock() noexcept
{
    static MonotonicServoClock clock;
    return clock;
}

ServoLoop::ServoLoop(NeedleForceModel& model, Device& device, const ServoOptions& options)
    : mModel(model), mDevice(device), mOpt(options), mClock(options.clock ? options.clock : &monotonicServoClock()),
      mStep(model, ServoStepOptions{.rateHz = options.rateHz, .watchdogS = options.watchdogS, .rampS = options.rampS}),
      mEvents(std::make_unique<SpscQueue<Event, 1024>>()), mRecords(std::make_unique<SpscQueue<ServoRecord, 1 << 16>>())
{
    mOpt.rateHz = mStep.options().rateHz; // a rate that is not positive and finite is 1 kHz
    mShaftEveryTicks = std::max(1L, std::lround(kShaftPublishS * mOpt.rateHz));
}

ServoLoop::~ServoLoop() { stop(); }

void ServoLoop::tick(double t, double dt, double lastPeriod) noexcept
{
    const std::int64_t start = mClock->nowNs();
    const DeviceReading r = mDevice.read(t);
    const Vec3d f = mStep.step(r, t, dt, lastPeriod);
    const NeedleOutput& out = mStep.output();
    for (const Event& e : out.events) mEvents->push(e), mDevice.event(e);
    mDevice.write(f, out.plungerN, t);

    ServoRecord rec;
    rec.timeS = t;
    rec.tip = r.tip;
    rec.direction = r.direction;
    rec.force = f;
    rec.plungerN = out.plungerN;
    rec.plungerFraction = r.plungerFraction;
    rec.rollRad = r.rollRad;
    rec.depthMm = out.tip.depthMm;
    rec.axialN = out.axialN;
    rec.layer = std::int16_t(out.tip.currentLayer());
    rec.state = rec.layer >= 0 ? mModel.state().state(rec.layer) : LayerState::Intact;
    rec.fault = out.fault;
    rec.critical = out.critical;
    mRecords->push(rec);

    // Counted in ticks, not seconds: a sum of periods drifts off the 10 ms marks.
    if (const BentNeedle* bent = mModel.bentNeedle();
        bent && mTicks.load(std::memory_order_relaxed) % mShaftEveryTicks == 0)
        mShaft.publish(bent->shaft());
    mLastForce.store(f.norm(), std::memory_order_relaxed);
    mLastLayer.store(rec.layer, std::memory_order_relaxed);
    mGainPublic.store(mStep.gain(), std::memory_order_relaxed);
    mTicks.fetch_add(1, std::memory_order_relaxed);
    const double ns = double(mClock->nowNs() - start);
    mStats.addCompute(ns);
    if (ns > mMaxComputeNs.load(std::memory_order_relaxed)) mMaxComputeNs.store(ns, std::memory_order_relaxed);
}

void ServoLoop::runTicks(long n) noexcept
{
    const double T = 1.0 / mOpt.rateHz;
    for (long i = 0; i < n && !mDevice.finished() && !mStep.released(); ++i) {
        tick(mSimTime, T, T);
        mSimTime += T;
    }
}

void ServoLoop::loop() noexcept
{
    const std::int64_t period = std::int64_t(std::llround(1e9 / mOpt.rateHz));
    ServoClock& clock = *mClock;
    std::int64_t t0 = clock.nowNs();
    bool first = true, behind = false; // behind: catching up on missed deadlines
    const bool spin = double(period) * 1e-9 <= mOpt.spinBelowS;
    prctl(PR_SET_TIMERSLACK, 1UL, 0, 0, 0); // wake at the deadline, not up to 50 µs after it
    if (mOpt.realtime) {                    // before the first tick; start() reports the outcome
        sched_param p{};
        p.sched_priority = mOpt.realtimePriority;
        const int rc = (mOpt.setScheduler ? mOpt.setScheduler : pthread_setschedparam)(pthread_self(), SCHED_FIFO, &p);
        mSchedError.store(rc);
    } else {
        mSchedError.store(0);
    }
    mInterruptionPhase.store(-1);
    if (spin && mOpt.alignToInterruptions && mClock == &monotonicServoClock()) {
        // Before the first tick, at the loop's own priority and CPU (InterruptionPhase.h).
        const auto phase = measureInterruptionPhase([&clock] { return clock.nowNs(); }, period);
        if (phase) {
            mInterruptionPhase.store(*phase);
            t0 = alignedGridStart(clock.nowNs(), period, *phase, std::llround(mOpt.interruptionLeadS * 1e9));
        } else {
            t0 = clock.nowNs();
        }
    }
    // The catch-up bound (ServoOptions::catchUpPeriods): by default what the watchdog
    // does not call a stall.
    const std::int64_t catchUp = mOpt.catchUpPeriods >= 0
        ? std::int64_t(mOpt.catchUpPeriods)
        : std::int64_t(std::floor(mOpt.watchdogS * 1e9 / double(period) + 1e-9));
    // A sleeping loop on the real clock wakes wakeLeadS early and spins to the deadline.
    const std::int64_t wakeLead = !spin && mClock == &monotonicServoClock()
        ? std::min(period / 2, std::int64_t(std::llround(std::max(0.0, mOpt.wakeLeadS) * 1e9)))
        : 0;
    std::int64_t deadline = t0, last = t0;
    while (!mStop.load(std::memory_order_relaxed) && !mDevice.finished() && !mStep.released()) {
        // Absolute deadlines: sleeping until t0 + n·T does not accumulate drift.
        if (wakeLead > 0) {
            clock.waitUntilNs(deadline - wakeLead, false);
            clock.waitUntilNs(deadline, true);
        } else {
            clock.waitUntilNs(deadline, spin);
        }
        const std::int64_t now = clock.nowNs();
        const std::int64_t actual = now - last;
        if (!first) mStats.addPeriodError(double(std::llabs(actual - period)));
        last = now;
        if (first) mFirstTickNs.store(now, std::memory_order_relaxed);
        mLastTickNs.store(now, std::memory_order_relaxed);
        tick(double(now - t0) * 1e-9, double(period) * 1e-9, first ? double(period) * 1e-9 : double(actual) * 1e-9);
        first = false;
        deadline += period;
        const std::int64_t after = clock.nowNs();
        if (after <= deadline) {
            behind = false;
            continue;
        }
        // Missed the next deadline: once per episode an overrun. Deadlines already
        // passed, the next one included: run them at once when they are few
        // (ServoOptions::catchUpPeriods), otherwise drop them and re-anchor the grid.
        if (!behind) mOverruns.fetch_add(1, std::memory_order_relaxed);
        const std::int64_t missed = (after - deadline) / period + 1;
        if (missed > catchUp) {
            mSkipped.fetch_add(long(missed), std::memory_order_relaxed);
            deadline += missed * period; // the first grid point after `after`
            behind = false;
        } else {
            behind = true;
        }
    }
    mRunning.store(false);
}

void ServoLoop::start()
{
    if (mRunning.exchange(true)) return;
    mStop.store(false);
    mRealtime = RealtimeStatus{};
    mRealtime.requested = mOpt.realtime;
    mRealtime.priority = mOpt.realtime ? mOpt.realtimePriority : 0;
    std::string why;
    if (mOpt.realtime && mOpt.lockMemory) {
        // Locked memory: no page fault on the servo path (current and future pages).
        mRealtime.memoryLocked = ::mlockall(MCL_CURRENT | MCL_FUTURE) == 0;
        if (!mRealtime.memoryLocked)
            why =
                std::string("memory not locked (") + std::strerror(errno) + "): grant CAP_IPC_LOCK or raise ulimit -l";
    }
    mSchedError.store(-1);
    mThread = std::thread([this] { loop(); });
    if (mOpt.pinCpu >= 0) {
        cpu_set_t set;
        CPU_ZERO(&set);
        CPU_SET(mOpt.pinCpu, &set);
        mRealtime.pinned = pthread_setaffinity_np(mThread.native_handle(), sizeof set, &set) == 0;
        if (!mRealtime.pinned)
            why += std::string(why.empty() ? "" : "; ") + "not pinned to CPU " + std::to_string(mOpt.pinCpu);
    }
    // The thread reports its scheduling before its first tick (never from the tick).
    while (mSchedError.load() < 0 && mRunning.load()) std::this_thread::yield();
    const int err = mSchedError.load();
    mRealtime.scheduled = mOpt.realtime && err == 0;
    if (mOpt.realtime && err != 0) {
        why = "real-time scheduling refused (" + std::string(std::strerror(err > 0 ? err : EPERM)) +
            "): the servo loop runs at normal priority; run as root, grant CAP_SYS_NICE (setcap "
            "cap_sys_nice,cap_ipc_lock+ep "
            "voxhap) or raise the rtprio limit (ulimit -r " +
            std::to_string(mOpt.realtimePriority) + ")" + (why.empty() ? "" : "; " + why);
    }
    mRealtime.why = why;
}

void ServoLoop::releaseAndStop()
{
    beginRelease();
    // The loop ends itself on the tick that sends zero (or when the device finishes).
    if (mThread.joinable()) mThread.join();
    mRunning.store(false);
}

void ServoLoop::stop()
{
    mStop.store(true);
    if (mThread.joinable()) mThread.join();
    mRunning.store(false);
}

} // namespace voxhap::haptic
