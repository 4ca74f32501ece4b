// SPDX-License-Identifier: Apache-2.0
/// @file TestSplitDampingMutant.cpp
/// @brief A mutant build: haptic/force/NeedleForceModel.cpp compiled with
/// VOXHAP_MUTANT_SPLIT_DAMPING, whose splitDamping renders viscosity beyond the
/// device's limit, so that the excess counts twice (§6.2), linked in place of the
/// library's own.
/// Every shipped case held to R1 or R5 must fail against its closed form alone,
/// since those closed forms compute β and the split from physics.md in regress's
/// own code. The same cases pass in the real build (regress.BuiltinSuitePasses,
/// CliRegress.ShippedSuiteKeepsThePinnedClosedForms).

#include "regress/Compare.h"

#include "haptic/force/NeedleForceModel.h"

#include <gtest/gtest.h>

namespace {

using namespace voxhap;
using namespace voxhap::regress;

TEST(SplitDampingMutant, IsTheOneLinkedHere)
{
    // §6.2 at b = 0.1 N·s/mm, b_dev = 0.005 N·s/mm, v = v_ref = 10 mm/s, cap 6 N:
    // viscous 0.05 N and friction 0.95 N; the mutant renders 1 N of viscosity.
    haptic::ForceTerms::Damping d;
    d.capN = 6.0;
    d.referenceSpeedMmPerS = 10.0;
    haptic::DeviceLimits device;
    device.maxDampingNsPerMm = 0.005;
    const haptic::DampingSplit s = haptic::splitDamping(d, device, 0.1, 10.0);
    EXPECT_DOUBLE_EQ(s.frictionN, 0.95);
    EXPECT_DOUBLE_EQ(s.viscousN, 1.0) << "not the mutant: the library's splitDamping was linked";
}

TEST(SplitDampingMutant, EveryR1AndR5CaseFailsItsClosedForm)
{
    // The cases of Kyung's damping scene, the model R1 and R5 describe (the pinned
    // list, tests/regress/closed-forms.txt, says which of them each rule holds).
    const Suite s = builtinSuite();
    std::vector<std::size_t> damping;
    for (std::size_t i = 0; i < s.cases.size(); ++i) {
        if (s.cases[i].scene == "kyung-damping") damping.push_back(i);
    }
    Runner runner(s, damping, {});
    const std::vector<CaseRun> runs = runner.run();
    std::size_t held = 0;
    for (std::size_t k = 0; k < damping.size(); ++k) {
        const Case& c = s.cases[damping[k]];
        // No baseline: the closed form is the only reference.
        const CaseReport r = compareCase(c, runs[k], std::nullopt);
        if (r.closedForm != "closed form: R1" && r.closedForm != "closed form: R5") continue;
        ++held;
        ASSERT_TRUE(r.first) << c.name << ": the mutant split passed " << r.closedForm;
        EXPECT_NE(r.first->against.find(r.closedForm.substr(13)), std::string::npos)
            << c.name << ": " << r.first->against;
    }
    EXPECT_GE(held, 26u) << "the shipped slab and sphere cases";
}

} // namespace
