// SPDX-License-Identifier: Apache-2.0
/// @file main.cpp
/// @brief What a haptic-device application writes to put voxhap's needle force in
/// its own servo loop. The device SDK (SimulatedDevice.h, the
/// stand-in for the hardware) owns the 1 kHz thread and calls servoCallback() with
/// the handle's pose; the callback asks voxhap for the force with one
/// haptic::ServoStep::step(): no voxhap thread, no allocation, no lock, no
/// exception. Everything that allocates (the scene, its volume and material field,
/// the force model) is built before the device starts; events and samples leave
/// the callback through lock-free queues to the main thread, which prints them.
///
///   device-loop [--scene NAME|FILE] [--seconds S] [--speed MM_PER_S]
///
/// Exits 1 when the callback called the allocator (CallbackAllocations.h counts
/// it), 2 on bad arguments.

#include "CallbackAllocations.h"
#include "SimulatedDevice.h"

#include "core/Version.h"
#include "haptic/scene/Scene.h"
#include "haptic/servo/ServoStep.h"
#include "haptic/servo/SpscQueue.h"
#include "volume/TissueTable.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <string>
#include <thread>
#include <vector>

namespace {

using voxhap::Vec3d;
namespace haptic = voxhap::haptic;

/// @brief One servo tick as the main thread sees it.
struct Sample {
    double timeS = 0, depthMm = 0, forceN = 0;
};

/// @brief What the callback reaches through its user pointer: voxhap's tick and the
/// queues out of the servo thread (single producer, single consumer, no lock).
struct Servo {
    haptic::ServoStep* step = nullptr;
    haptic::SpscQueue<haptic::Event, 256> events;
    haptic::SpscQueue<Sample, 8192> samples; ///< 8 s at 1 kHz: the main thread drains it every 5 ms
};

// The device's servo thread, once per period.
void servoCallback(const simdev::HandleState& s, double forceN[3], void* user)
{
    const alloccheck::CountAllocations counting; // the check, not needed to embed voxhap
    Servo& servo = *static_cast<Servo*>(user);
    haptic::DeviceReading r;
    r.tip = Vec3d(s.position[0], s.position[1], s.position[2]);
    r.direction = Vec3d(s.direction[0], s.direction[1], s.direction[2]);
    r.velocity = Vec3d(s.velocity[0], s.velocity[1], s.velocity[2]);
    r.valid = true; // an SDK that can report a stale or lost handle sets valid and lost
    const Vec3d f = servo.step->step(r, s.timeS);
    const haptic::NeedleOutput& out = servo.step->output();
    for (const haptic::Event& e : out.events) servo.events.push(e);
    servo.samples.push(Sample{s.timeS, out.tip.depthMm, f.norm()});
    for (int i = 0; i < 3; ++i) forceN[i] = f[i];
}

haptic::ServoStep* gServo = nullptr;
extern "C" void onSignal(int) { gServo->beginRelease(); } // an atomic store: safe in a handler

[[noreturn]] void usage(const std::string& why)
{
    std::fprintf(stderr, "device-loop: %s\nusage: device-loop [--scene NAME|FILE] [--seconds S] [--speed MM_PER_S]\n",
        why.c_str());
    std::exit(2);
}

double positive(const char* flag, const char* text)
{
    char* end = nullptr;
    const double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !(v > 0.0) || v > 1e6)
        usage(std::string(flag) + ": not a positive number: " + text);
    return v;
}

} // namespace

int main(int argc, char** argv)
{
    std::string sceneName = "senac-average";
    double seconds = 1.5, speedMmPerS = 20.0;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        if (i + 1 >= argc) usage(a + ": missing value or unknown option");
        if (a == "--scene")
            sceneName = argv[++i];
        else if (a == "--seconds")
            seconds = positive("--seconds", argv[++i]);
        else if (a == "--speed")
            speedMmPerS = positive("--speed", argv[++i]);
        else
            usage("unknown option " + a);
    }

    // Set-up, before the device starts: everything that allocates, reads files or throws.
    std::unique_ptr<haptic::SceneInstance> scene;
    std::unique_ptr<haptic::NeedleForceModel> model;
    const auto t0 = std::chrono::steady_clock::now();
    try {
        scene = std::make_unique<haptic::SceneInstance>(
            haptic::loadScene(sceneName), nullptr, voxhap::volume::TissueTable::builtin());
        model = scene->makeModel();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "device-loop: %s\n", e.what());
        return 1;
    }
    const double setupS = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double rateHz = 1000.0;
    haptic::ServoStep step(*model, haptic::ServoStepOptions{.rateHz = rateHz});
    auto servo = std::make_unique<Servo>(); // the queues are large: on the heap, not the stack
    servo->step = &step;
    gServo = &step;
    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);

    // The hand pushes the needle along the scene's path from 5 mm outside the entry.
    simdev::Hand hand;
    const haptic::NeedlePath& path = model->path();
    for (int i = 0; i < 3; ++i) hand.origin[i] = path.origin[i], hand.direction[i] = path.direction[i];
    hand.speedMmPerS = speedMmPerS;
    std::printf("voxhap %s, scene %s (device %s): set up in %.2f s\n", std::string(voxhap::kVersion).c_str(),
        scene->scene().name.c_str(), model->device().name.c_str(), setupS);
    std::printf("simulated hand from %.1f mm at %.1f mm/s for %.2f s; the device calls back at %.0f Hz\n", hand.startMm,
        speedMmPerS, seconds, rateHz);

    // Run: the device's thread calls servoCallback; this thread only drains the queues.
    simdev::SimulatedDevice device(hand, rateHz);
    std::vector<Sample> samples;
    samples.reserve(std::size_t(seconds * rateHz) + 1000);
    double skinContactS = -1, skinEntryS = -1;
    auto drain = [&] {
        haptic::Event e;
        while (servo->events.pop(e)) {
            std::printf("  %6.3f s  %-18s at %6.2f mm\n", e.timeS, haptic::eventName(e.type), e.depthMm);
            if (e.type == haptic::EventType::SkinContact && skinContactS < 0) skinContactS = e.timeS;
            if (e.type == haptic::EventType::SkinEntry && skinEntryS < 0) skinEntryS = e.timeS;
        }
        Sample s;
        while (servo->samples.pop(s)) samples.push_back(s);
    };
    device.start(servoCallback, servo.get());
    const long ticks = long(seconds * rateHz);
    while (device.ticks() < ticks && !step.releasing()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
        drain();
    }
    // Ramp the force down before letting go of the device (physics.md §6.3), then stop.
    step.beginRelease();
    while (!step.released()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    device.stop();
    drain();

    // The force along the way, and what the callback cost the allocator.
    std::printf("force against depth, every 0.1 s:\n  t [s]  depth [mm]  force [N]\n");
    for (const Sample& s : samples) {
        const long ms = std::lround(s.timeS * 1000.0);
        if (ms % 100 == 0) std::printf("  %5.2f  %10.2f  %9.3f\n", s.timeS, s.depthMm, s.forceN);
    }
    // In air, and while the skin tents: from contact up to the tick it gives way.
    double inAir = 0.0, tenting = 0.0, tentingDepth = 0.0;
    for (const Sample& s : samples) {
        if (skinContactS < 0 || s.timeS < skinContactS) inAir = std::max(inAir, s.forceN);
        const bool tents = skinContactS >= 0 && s.timeS >= skinContactS && (skinEntryS < 0 || s.timeS < skinEntryS);
        if (tents && s.forceN > tenting) tenting = s.forceN, tentingDepth = s.depthMm;
    }
    std::printf("force in air before skin contact: max %.6f N\n", inAir);
    if (skinEntryS < 0)
        std::printf("force at skin puncture: none (the needle did not enter the skin)\n");
    else if (skinEntryS <= skinContactS)
        std::printf("force at skin puncture: none (the skin gave way on contact, without tenting)\n");
    else
        std::printf(
            "force at skin puncture: %.3f N at %.2f mm (the highest while the skin tented)\n", tenting, tentingDepth);
    const long calls = alloccheck::allocations(), frees = alloccheck::frees();
    std::printf("allocator calls in the callback: %ld allocations, %ld frees in %ld ticks (%ld late)\n", calls, frees,
        device.ticks(), device.late());

    // The counter itself counts: one operator new and delete in a counted scope.
    {
        const alloccheck::CountAllocations counting;
        ::operator delete(::operator new(64));
    }
    std::printf("allocation counter check: %ld allocation, %ld free for one operator new and delete\n",
        alloccheck::allocations() - calls, alloccheck::frees() - frees);
    if (calls != 0 || frees != 0) {
        std::fprintf(stderr, "device-loop: the servo callback called the allocator\n");
        return 1;
    }
    return 0;
}
