// SPDX-License-Identifier: Apache-2.0
/// @file TestClassifier.cpp
/// @brief The logistic regression against closed forms (a binary feature's
/// maximum-likelihood fit, a two-point ridge fit's fixed point, the stationarity
/// conditions), the Wilson interval against hand-computed values, cross-validation
/// and the labelled CSV's refusals (issue 23 item 3).

#include "assessment/Classifier.h"
#include "core/Errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace voxhap::assessment {
namespace {

/// Newton's method stops when no coefficient moves by more than 1e-10; at that
/// point a quadratically converging fit is ~1e-20 from its optimum, and a
/// probability σ(t) moves by at most |Δt|/4. 1e-9 is round-off of sums over tens of
/// samples plus that, with room.
constexpr double kFitTolerance = 1e-9;
/// Hand-computed interval bounds printed to 4 decimals: half a unit of the last digit.
constexpr double kFourDecimals = 5e-5;

LabelledSet set(std::vector<std::vector<double>> x, std::vector<int> y)
{
    LabelledSet d;
    d.origin = "test";
    for (std::size_t j = 0; j < x.front().size(); ++j) d.features.push_back("f" + std::to_string(j));
    d.x = std::move(x);
    d.y = std::move(y);
    return d;
}

double sigmoid(double t) { return 1.0 / (1.0 + std::exp(-t)); }

// One binary feature: the maximum-likelihood fit reproduces each group's positive
// fraction, P(1|x=0) = 3/10 and P(1|x=1) = 6/8, so the raw slope is
// logit(3/4) − logit(3/10) = ln 3 − ln(3/7) = ln 7 and the raw intercept ln(3/7).
TEST(LogisticRegression, BinaryFeatureMatchesTheGroupFractions)
{
    std::vector<std::vector<double>> x;
    std::vector<int> y;
    for (int i = 0; i < 10; ++i) x.push_back({0.0}), y.push_back(i < 3);
    for (int i = 0; i < 8; ++i) x.push_back({1.0}), y.push_back(i < 6);
    TrainOptions o;
    o.lambda = 0.0;
    const LogisticModel m = trainLogistic(set(x, y), o);
    EXPECT_NEAR(m.probability({0.0}), 0.3, kFitTolerance);
    EXPECT_NEAR(m.probability({1.0}), 0.75, kFitTolerance);
    const double rawSlope = m.weights[0] / m.scale[0];
    EXPECT_NEAR(rawSlope, std::log(7.0), kFitTolerance);
    EXPECT_NEAR(m.intercept - rawSlope * m.mean[0], std::log(3.0 / 7.0), kFitTolerance);
}

// A constant feature carries no information: weight 0 and P = the positive fraction.
TEST(LogisticRegression, ConstantFeatureGivesThePositiveFraction)
{
    const LogisticModel m = trainLogistic(set({{2}, {2}, {2}, {2}, {2}}, {1, 0, 1, 0, 0}), {});
    EXPECT_EQ(m.weights[0], 0.0);
    EXPECT_NEAR(m.probability({2.0}), 0.4, kFitTolerance);
}

// x = −1, +1 with labels 0, 1 and λ = 1: standardised z = x, the intercept is 0 by
// symmetry, and the stationarity condition −σ(−w) + (σ(w) − 1) + λw = 0 gives the
// fixed point w = 2σ(−w), w = 0.674832 (iterated by hand to six digits).
TEST(LogisticRegression, TwoPointRidgeFitSolvesItsFixedPoint)
{
    TrainOptions o;
    o.lambda = 1.0;
    const LogisticModel m = trainLogistic(set({{-1}, {1}}, {0, 1}), o);
    EXPECT_NEAR(m.intercept, 0.0, kFitTolerance);
    EXPECT_NEAR(m.weights[0], 2.0 * sigmoid(-m.weights[0]), kFitTolerance);
    EXPECT_NEAR(m.weights[0], 0.674832, 5e-7); // half a unit of the sixth decimal
}

// With a penalty the fit is still a stationary point: Σ(p − y) = 0 (the intercept is
// not penalised) and Σ(p − y)·z_j + λ·w_j = 0, computed here independently of the solver.
TEST(LogisticRegression, RidgeFitIsStationary)
{
    const LabelledSet d = set(
        {{0.1, 3}, {0.4, 1}, {0.35, 2}, {0.8, 2}, {0.9, 5}, {0.2, 4}, {0.7, 1}, {0.6, 3}}, {0, 0, 1, 1, 1, 0, 0, 1});
    TrainOptions o;
    o.lambda = 0.5;
    const LogisticModel m = trainLogistic(d, o);
    double g0 = 0, g1 = 0, g2 = 0;
    for (std::size_t i = 0; i < d.x.size(); ++i) {
        const double r = m.probability(d.x[i]) - d.y[i];
        g0 += r;
        g1 += r * (d.x[i][0] - m.mean[0]) / m.scale[0];
        g2 += r * (d.x[i][1] - m.mean[1]) / m.scale[1];
    }
    EXPECT_NEAR(g0, 0.0, kFitTolerance);
    EXPECT_NEAR(g1 + o.lambda * m.weights[0], 0.0, kFitTolerance);
    EXPECT_NEAR(g2 + o.lambda * m.weights[1], 0.0, kFitTolerance);
}

TEST(LogisticRegression, SeparableClassesNeedAPenalty)
{
    TrainOptions o;
    o.lambda = 0.0;
    try {
        trainLogistic(set({{0}, {1}, {2}, {3}}, {0, 0, 1, 1}), o);
        FAIL() << "a separable fit with lambda 0 converged";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("give lambda > 0"), std::string::npos) << e.what();
    }
    EXPECT_NO_THROW(trainLogistic(set({{0}, {1}, {2}, {3}}, {0, 0, 1, 1}), {}));
}

TEST(LogisticRegression, ModelJsonRoundTripGivesTheSameProbabilities)
{
    const LabelledSet d = set({{0.1, 3}, {0.4, 1}, {0.35, 2}, {0.8, 2}, {0.9, 5}}, {0, 0, 1, 1, 1});
    const LogisticModel m = trainLogistic(d, {});
    const LogisticModel back = LogisticModel::fromJson(nlohmann::json::parse(m.toJson().dump()), "model.json");
    for (const auto& x : d.x) EXPECT_DOUBLE_EQ(back.probability(x), m.probability(x));
    nlohmann::json bad = m.toJson();
    bad["weights"] = {1.0};
    EXPECT_THROW(LogisticModel::fromJson(bad, "model.json"), ValueError);
}

// Wilson score intervals computed by hand from the formula (z = 1.959964).
TEST(WilsonInterval, MatchesHandComputedValues)
{
    const Interval a = wilsonInterval(8, 10);
    EXPECT_NEAR(a.low, 0.4902, kFourDecimals);
    EXPECT_NEAR(a.high, 0.9433, kFourDecimals);
    const Interval b = wilsonInterval(0, 10);
    EXPECT_NEAR(b.low, 0.0, kFourDecimals);
    EXPECT_NEAR(b.high, 0.2775, kFourDecimals);
    const Interval c = wilsonInterval(10, 10);
    EXPECT_NEAR(c.low, 0.7225, kFourDecimals);
    EXPECT_NEAR(c.high, 1.0, kFourDecimals);
    const Interval d = wilsonInterval(50, 100);
    EXPECT_NEAR(d.low, 0.4038, kFourDecimals);
    EXPECT_NEAR(d.high, 0.5962, kFourDecimals);
}

// Two groups far apart on one feature: every held-out sample is classified right,
// so the accuracy is 1 and the interval Wilson's for n out of n.
TEST(CrossValidation, SeparatedGroupsAreAllRight)
{
    std::vector<std::vector<double>> x;
    std::vector<int> y;
    for (int i = 0; i < 10; ++i) x.push_back({double(i % 3)}), y.push_back(0);
    for (int i = 0; i < 10; ++i) x.push_back({10.0 + i % 3}), y.push_back(1);
    const CrossValidation cv = crossValidate(set(x, y), 5);
    EXPECT_EQ(cv.correct, 20);
    EXPECT_EQ(cv.n, 20);
    EXPECT_NEAR(cv.ci95.low, wilsonInterval(20, 20).low, 1e-15);
    EXPECT_THROW(crossValidate(set(x, y), 1), ValueError);
    EXPECT_THROW(crossValidate(set(x, y), 21), ValueError);
}

} // namespace
} // namespace voxhap::assessment
