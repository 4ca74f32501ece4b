// SPDX-License-Identifier: Apache-2.0
/// @file ServoBench.cpp
#include "bench/ServoBench.h"

#include "bench/SamplerBench.h"
#include "haptic/devices/SimulatedDevices.h"
#include "haptic/igtl/IgtlDevice.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoLoop.h"

#include <igtlTransformMessage.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <memory>
#include <thread>

namespace voxhap::bench {

namespace {

/// One real-time run: a reckless hand at 5 mm/s goes through every layer of the path
/// (tenting, pops, LOR, dura) and on; the queues are drained as `voxhap serve` does.
/// Host steal time so far, all CPUs [s]: the 8th value of /proc/stat's "cpu" line.
/// The kernel's real-time bandwidth: a SCHED_FIFO thread gets at most
/// sched_rt_runtime_us of every sched_rt_period_us (Linux default 950 000 of
/// 1 000 000), so a loop that spins (periods up to 100 us) loses the rest of each
/// second; -1 lifts the limit, as dedicated real-time rigs set it.
std::string rtBandwidth()
{
    std::ifstream runtime("/proc/sys/kernel/sched_rt_runtime_us"), period("/proc/sys/kernel/sched_rt_period_us");
    long r = 0, p = 0;
    if (!(runtime >> r) || !(period >> p)) return "unknown";
    if (r < 0) return "unlimited (sched_rt_runtime_us = -1)";
    return std::to_string(r) + " us of every " + std::to_string(p) + " us (sched_rt_runtime_us; -1 lifts it)";
}

double stealSeconds()
{
    std::ifstream in("/proc/stat");
    std::string cpu;
    double v[8] = {};
    in >> cpu;
    for (double& x : v) in >> x;
    return cpu == "cpu" ? v[7] / double(::sysconf(_SC_CLK_TCK)) : 0.0;
}

/// N busy-loop processes at normal priority for the life of the object.
class BusyLoad {
public:
    explicit BusyLoad(int n)
    {
        for (int i = 0; i < n; ++i) {
            const pid_t pid = ::fork();
            if (pid == 0) {
                ::prctl(PR_SET_PDEATHSIG, SIGKILL); // never outlive the benchmark
                volatile unsigned long spin = 0;
                for (;;) spin = spin + 1;
            }
            if (pid > 0) mPids.push_back(pid);
        }
    }
    ~BusyLoad()
    {
        for (const pid_t p : mPids) ::kill(p, SIGKILL);
        for (const pid_t p : mPids) ::waitpid(p, nullptr, 0);
    }
    BusyLoad(const BusyLoad&) = delete;
    BusyLoad& operator=(const BusyLoad&) = delete;

private:
    std::vector<pid_t> mPids;
};

ServoRun runOnce(
    const haptic::SceneInstance& inst, double rateHz, double seconds, const ServoBenchOptions& o, std::string* note)
{
    auto model = inst.makeModel();
    haptic::HandParams p;
    p.speedMmPerS = 5.0;
    p.stopOnLor = false;
    haptic::HandDevice hand(model->path(), p, model->device());
    haptic::ServoOptions so;
    so.rateHz = rateHz;
    so.realtime = o.realtime;
    so.catchUpPeriods = o.catchUpPeriods;
    so.pinCpu = o.pinCpu;
    so.alignToInterruptions = o.align;
    haptic::ServoLoop loop(*model, hand, so);
    const double steal0 = stealSeconds();
    const auto t0 = std::chrono::steady_clock::now();
    loop.start();
    if (note && !loop.realtimeStatus().why.empty()) *note = loop.realtimeStatus().why;
    haptic::ServoRecord rec;
    haptic::Event ev;
    while (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() < seconds) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        while (loop.popRecord(rec)) { }
        while (loop.popEvent(ev)) { }
    }
    loop.stop();
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ServoRun r;
    r.scene = inst.scene().name;
    r.rateHz = rateHz;
    r.seconds = wall;
    r.ticks = loop.ticks();
    // The loop's own rate: ticks over the window from its first tick to its last. The
    // set-up before the first tick (mlockall of the whole process, the scheduler call)
    // happens once per session and is reported apart, not spread over the rate.
    const double ticking = loop.tickingSeconds();
    r.achievedHz = r.ticks > 1 && ticking > 0.0 ? double(r.ticks - 1) / ticking : 0.0;
    r.startS = wall - ticking;
    r.overruns = loop.overruns();
    r.skipped = loop.skippedPeriods();
    r.phaseUs = loop.interruptionPhaseNs() < 0 ? -1.0 : double(loop.interruptionPhaseNs()) * 1e-3;
    r.computeP50Ns = loop.stats().computeQuantileNs(0.5);
    r.computeP99Ns = loop.stats().computeQuantileNs(0.99);
    r.computeMaxNs = loop.maxComputeNs();
    r.periodErrP50Ns = loop.stats().jitterQuantileNs(0.5);
    r.periodErrP99Ns = loop.stats().jitterQuantileNs(0.99);
    r.realtime = loop.realtimeStatus().scheduled;
    r.stealS = stealSeconds() - steal0;
    return r;
}

/// A loopback client sends a TRANSFORM every millisecond and waits for the SENSOR reply.
IgtlRoundTrip igtlRoundTrip(const haptic::SceneInstance& inst, double seconds)
{
    auto model = inst.makeModel();
    haptic::IgtlOptions io;
    io.port = 0;
    haptic::IgtlDevice dev(io, model->device());
    haptic::ServoLoop loop(*model, dev);
    loop.start();
    IgtlRoundTrip out;
    const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(std::uint16_t(dev.port()));
    ::inet_pton(AF_INET, "127.0.0.1", &a.sin_addr);
    const int one = 1;
    ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
        ::close(fd);
        loop.stop();
        return out;
    }
    const auto readExactly = [fd](unsigned char* p, std::size_t n) {
        for (std::size_t got = 0; got < n;) {
            pollfd q{fd, POLLIN, 0};
            if (::poll(&q, 1, 100) <= 0) return false;
            const ssize_t r = ::recv(fd, p + got, n - got, 0);
            if (r <= 0) return false;
            got += std::size_t(r);
        }
        return true;
    };
    auto msg = igtl::TransformMessage::New();
    msg->SetDeviceName("Needle");
    std::vector<double> rtt;
    const Vec3d e = inst.entry(), u = (inst.target() - inst.entry()).normalized();
    const auto t0 = std::chrono::steady_clock::now();
    for (long n = 0;; ++n) {
        const auto due = t0 + std::chrono::microseconds(1000 * n);
        if (std::chrono::duration<double>(due - t0).count() > seconds) break;
        std::this_thread::sleep_until(due);
        igtl::Matrix4x4 m;
        igtl::IdentityMatrix(m);
        const Vec3d tip = e + (-5.0 + 0.005 * double(n % 8000)) * u; // in and out along the path at 5 mm/s
        m[0][3] = float(tip.x()), m[1][3] = float(tip.y()), m[2][3] = float(tip.z());
        m[0][2] = float(u.x()), m[1][2] = float(u.y()), m[2][2] = float(u.z());
        msg->SetMatrix(m);
        msg->Pack();
        const auto sent = std::chrono::steady_clock::now();
        if (::send(fd, msg->GetPackPointer(), std::size_t(msg->GetPackSize()), MSG_NOSIGNAL) < 0) break;
        bool got = false;
        unsigned char h[58];
        std::vector<unsigned char> body;
        while (readExactly(h, 58)) {
            std::uint64_t size = 0;
            for (int i = 42; i < 50; ++i) size = (size << 8) | h[i];
            body.resize(std::size_t(size));
            if (!readExactly(body.data(), body.size())) break;
            if (std::strncmp(reinterpret_cast<const char*>(h) + 2, "SENSOR", 12) == 0) {
                got = true;
                break;
            }
        }
        if (got)
            rtt.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - sent).count());
        else
            ++out.lost;
    }
    ::close(fd);
    loop.stop();
    out.samples = long(rtt.size());
    if (!rtt.empty()) {
        std::sort(rtt.begin(), rtt.end());
        out.p50Us = rtt[rtt.size() / 2];
        out.p99Us = rtt[std::min(rtt.size() - 1, std::size_t(0.99 * double(rtt.size())))];
        out.maxUs = rtt.back();
    }
    return out;
}

/// A thread that spins on the monotonic clock for @p seconds, at SCHED_FIFO when
/// asked and allowed (as the servo thread), and counts the gaps between two readings:
/// time the machine (interrupts, the scheduler tick, the host's own scheduling of a
/// virtual CPU) took from a thread that asked for nothing else.
InterruptionFloor measureInterruptionFloor(double seconds, bool realtime, int pinCpu)
{
    InterruptionFloor f;
    f.seconds = seconds;
    const std::vector<double> thresholdsUs{5, 10, 19, 50, 100, 500, 1000};
    std::vector<long> counts(thresholdsUs.size(), 0);
    const double steal0 = stealSeconds();
    std::thread probe([&] {
        if (realtime) {
            sched_param p{};
            p.sched_priority = haptic::ServoOptions{}.realtimePriority;
            f.realtime = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
        }
        if (pinCpu >= 0) {
            cpu_set_t set;
            CPU_ZERO(&set);
            CPU_SET(pinCpu, &set);
            pthread_setaffinity_np(pthread_self(), sizeof set, &set);
        }
        haptic::ServoClock& clock = haptic::monotonicServoClock();
        const std::int64_t t0 = clock.nowNs(), end = t0 + std::int64_t(seconds * 1e9);
        std::int64_t last = t0, maxGap = 0;
        for (std::int64_t t = t0; t < end; last = t) {
            t = clock.nowNs();
            const std::int64_t gap = t - last;
            if (gap > 5000)
                for (std::size_t i = 0; i < thresholdsUs.size(); ++i)
                    if (double(gap) > thresholdsUs[i] * 1e3) ++counts[i];
            maxGap = std::max(maxGap, gap);
        }
        f.maxGapUs = double(maxGap) * 1e-3;
    });
    probe.join();
    f.stealS = stealSeconds() - steal0;
    for (std::size_t i = 0; i < thresholdsUs.size(); ++i)
        f.gapsPerSecond.emplace_back(thresholdsUs[i], double(counts[i]) / seconds);
    return f;
}

} // namespace

ServoReport runServoBench(const ServoBenchOptions& o, const Progress& progress)
{
    ServoReport report;
    report.machine = machineDescription();
    report.rtBandwidth = rtBandwidth();
    report.load = o.load;
    report.catchUpPeriods = o.catchUpPeriods;
    const BusyLoad load(o.load); // beside every run, ladder included
    if (o.floorSeconds > 0.0) {
        if (progress) progress(-1.0, "interruption floor: a real-time thread that only reads the clock");
        report.floor = measureInterruptionFloor(o.floorSeconds, o.realtime, o.pinCpu);
    }
    const auto& table = volume::TissueTable::builtin();
    for (const std::string& name : o.scenes) {
        if (progress) progress(-1.0, "building " + name);
        const haptic::SceneInstance inst(haptic::loadScene(name), nullptr, table);
        if (progress) progress(-1.0, name + ": 1 kHz for " + std::to_string(int(o.seconds)) + " s");
        std::vector<ServoRun> runs;
        for (int k = 0; k < std::max(1, o.repeats); ++k) {
            if (progress && o.repeats > 1)
                progress(-1.0, name + ": 1 kHz run " + std::to_string(k + 1) + " of " + std::to_string(o.repeats));
            runs.push_back(runOnce(inst, 1000.0, o.seconds, o, &report.realtimeNote));
            report.runs.push_back(runs.back());
        }
        // The median of each figure over the runs (runs with steal are kept, and show it).
        const auto median = [&](auto field) {
            std::vector<double> v;
            for (const ServoRun& r : runs) v.push_back(double(r.*field));
            std::sort(v.begin(), v.end());
            return v[v.size() / 2];
        };
        ServoRun m = runs.front();
        m.achievedHz = median(&ServoRun::achievedHz);
        m.periodErrP99Ns = median(&ServoRun::periodErrP99Ns);
        m.periodErrP50Ns = median(&ServoRun::periodErrP50Ns);
        m.overruns = long(median(&ServoRun::overruns));
        m.skipped = long(median(&ServoRun::skipped));
        m.ticks = long(median(&ServoRun::ticks));
        m.computeP99Ns = median(&ServoRun::computeP99Ns);
        m.stealS = median(&ServoRun::stealS);
        report.median.push_back(m);
        // The highest sustained rate of each full ladder; reported: their median.
        std::vector<double> bests;
        for (int k = 0; k < std::max(1, o.ladderRepeats); ++k) {
            double best = 0.0;
            for (const double rate : o.rates) {
                if (progress) progress(-1.0, name + ": " + std::to_string(int(rate)) + " Hz");
                const ServoRun r = runOnce(inst, rate, o.ladderSeconds, o, nullptr);
                report.ladder.push_back(r);
                // Sustained: the rate achieved within 1 % and fewer than 0.1 % of ticks overrun.
                if (r.achievedHz >= 0.99 * rate && double(r.overruns) <= 1e-3 * double(r.ticks)) best = rate;
            }
            bests.push_back(best);
        }
        report.sustainedPerLadder.emplace_back(name, bests);
        std::sort(bests.begin(), bests.end());
        report.sustainableHz.emplace_back(name, bests[bests.size() / 2]);
        if (name == o.scenes.front() && o.igtlSeconds > 0.0) {
            if (progress) progress(-1.0, name + ": OpenIGTLink round trip");
            report.igtl = igtlRoundTrip(inst, o.igtlSeconds);
        }
    }
    return report;
}

namespace {
double gapsOver(const InterruptionFloor& f, double us)
{
    for (const auto& [t, n] : f.gapsPerSecond)
        if (t == us) return n;
    return 0.0;
}
} // namespace

void printServoReport(std::ostream& os, const ServoReport& r)
{
    os << "machine: " << r.machine << "\n\n";
    const auto row = [&](const ServoRun& x) {
        os << std::left << std::setw(16) << x.scene << std::right << std::fixed << std::setprecision(0) << std::setw(9)
           << x.rateHz << std::setw(10) << x.achievedHz << std::setw(9) << x.ticks << std::setw(9) << x.overruns
           << std::setw(9) << x.skipped << std::setprecision(2) << std::setw(10) << x.computeP50Ns * 1e-3
           << std::setw(10) << x.computeP99Ns * 1e-3 << std::setw(10) << x.computeMaxNs * 1e-3 << std::setw(10)
           << x.periodErrP50Ns * 1e-3 << std::setw(10) << x.periodErrP99Ns * 1e-3 << std::setprecision(3)
           << std::setw(9) << x.startS;
        if (x.phaseUs >= 0.0) os << std::setprecision(2) << std::setw(9) << x.phaseUs;
        os << '\n';
    };
    const auto header = [&] {
        os << std::left << std::setw(16) << "scene" << std::right << std::setw(9) << "rate" << std::setw(10)
           << "achieved" << std::setw(9) << "ticks" << std::setw(9) << "overrun" << std::setw(9) << "skipped"
           << std::setw(10) << "p50 us" << std::setw(10) << "p99 us" << std::setw(10) << "max us" << std::setw(10)
           << "jit50 us" << std::setw(10) << "jit99 us" << std::setw(9) << "start s" << std::setw(9) << "phase us"
           << '\n';
    };
    os << "kernel real-time bandwidth: " << r.rtBandwidth << "\n";
    os << "load: " << r.load << " busy process(es) beside the loop; real-time scheduling "
       << (r.runs.empty() || !r.runs.front().realtime ? "not granted" : "granted (SCHED_FIFO)") << '\n';
    if (!r.realtimeNote.empty()) os << "  " << r.realtimeNote << '\n';
    os << "catch-up: missed deadlines up to "
       << (r.catchUpPeriods < 0 ? std::string("the watchdog's 20 ms") : std::to_string(r.catchUpPeriods) + " period(s)")
       << " behind run late; longer stalls drop their periods (skipped)\n"
       << "phase us: spinning loops start their grid so that each tick ends before the phase of the period at which\n"
       << "  the machine was seen to interrupt them (InterruptionPhase.h); blank: not aligned\n";
    os << "1 kHz servo loop, simulated hand (tick compute; period error; host steal time per run)\n";
    header();
    for (const ServoRun& x : r.runs) {
        row(x);
        os << std::setprecision(2) << "    steal " << x.stealS << " s\n";
    }
    if (r.runs.size() > r.median.size()) {
        os << "median of the runs per scene (targets: achieved >= 999.5 Hz, jitter p99 <= 50 us, overruns <= 0.1 %)\n";
        header();
        for (const ServoRun& x : r.median) row(x);
    }
    os << "\nrate ladder\n";
    header();
    for (const ServoRun& x : r.ladder) row(x);
    os << "\nhighest sustained rate (achieved within 1 %, overruns < 0.1 %), median over full ladders:\n";
    for (std::size_t i = 0; i < r.sustainableHz.size(); ++i) {
        os << "  " << r.sustainableHz[i].first << ": " << std::setprecision(0) << r.sustainableHz[i].second << " Hz";
        if (i < r.sustainedPerLadder.size() && r.sustainedPerLadder[i].second.size() > 1) {
            os << " (ladders:";
            for (const double hz : r.sustainedPerLadder[i].second) os << ' ' << hz;
            os << ")";
        }
        os << '\n';
    }
    if (r.floor.seconds > 0.0) {
        os << "\ninterruption floor: a " << (r.floor.realtime ? "SCHED_FIFO" : "normal-priority")
           << " thread that only reads the clock, " << std::setprecision(0) << r.floor.seconds
           << " s; gaps per second longer than:\n ";
        for (const auto& [us, n] : r.floor.gapsPerSecond)
            os << "  " << std::setprecision(0) << us << " us: " << std::setprecision(1) << n;
        os << "\n  longest " << std::setprecision(0) << r.floor.maxGapUs << " us; host steal " << std::setprecision(2)
           << r.floor.stealS << " s. A loop overruns at least as often as gaps exceed its period less its tick:\n"
           << "  gaps > 19 us are " << std::setprecision(3) << gapsOver(r.floor, 19) / 500.0
           << " % of the ticks at 50 kHz (bound 0.1 %)\n";
    }
    os << "\nOpenIGTLink pose -> force round trip on loopback at 1 kHz, servo running: " << r.igtl.samples
       << " samples, " << r.igtl.lost << " lost; p50 " << std::setprecision(1) << r.igtl.p50Us << " us, p99 "
       << r.igtl.p99Us << " us, max " << r.igtl.maxUs << " us\n";
}

nlohmann::json servoReportJson(const ServoReport& r)
{
    const auto run = [](const ServoRun& x) {
        return nlohmann::json{{"scene", x.scene}, {"rate_hz", x.rateHz}, {"achieved_hz", x.achievedHz},
            {"seconds", x.seconds}, {"outside_ticking_s", x.startS}, {"ticks", x.ticks}, {"overruns", x.overruns},
            {"skipped_periods", x.skipped}, {"interruption_phase_us", x.phaseUs}, {"compute_p50_ns", x.computeP50Ns},
            {"compute_p99_ns", x.computeP99Ns}, {"compute_max_ns", x.computeMaxNs},
            {"period_error_p50_ns", x.periodErrP50Ns}, {"period_error_p99_ns", x.periodErrP99Ns},
            {"realtime", x.realtime}, {"steal_s", x.stealS}};
    };
    nlohmann::json j{{"machine", r.machine}, {"rt_bandwidth", r.rtBandwidth}, {"load", r.load},
        {"realtime_note", r.realtimeNote}, {"catch_up_periods", r.catchUpPeriods}};
    for (const auto& x : r.median) j["median"].push_back(run(x));
    for (const auto& x : r.runs) j["runs"].push_back(run(x));
    for (const auto& x : r.ladder) j["ladder"].push_back(run(x));
    for (const auto& [scene, hz] : r.sustainableHz) j["sustainable_hz"][scene] = hz;
    if (r.floor.seconds > 0.0) {
        nlohmann::json g = nlohmann::json::object();
        for (const auto& [us, n] : r.floor.gapsPerSecond) g[std::to_string(int(us)) + "us"] = n;
        j["interruption_floor"] = {{"seconds", r.floor.seconds}, {"realtime", r.floor.realtime},
            {"gaps_per_second_longer_than", g}, {"max_gap_us", r.floor.maxGapUs}, {"steal_s", r.floor.stealS}};
    }
    j["igtl_round_trip"] = {{"samples", r.igtl.samples}, {"lost", r.igtl.lost}, {"p50_us", r.igtl.p50Us},
        {"p99_us", r.igtl.p99Us}, {"max_us", r.igtl.maxUs}};
    return j;
}

} // namespace voxhap::bench
