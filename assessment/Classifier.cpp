// SPDX-License-Identifier: Apache-2.0
/// @file Classifier.cpp
/// @brief Logistic regression by Newton's method, cross-validation and the Wilson interval.

#include "assessment/Classifier.h"

#include "core/Errors.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <numeric>
#include <random>
#include <sstream>

namespace voxhap::assessment {

namespace {

double sigmoid(double t) { return t >= 0 ? 1.0 / (1.0 + std::exp(-t)) : std::exp(t) / (1.0 + std::exp(t)); }

/// ln(1 + e^t) without overflow.
double softplus(double t) { return t > 0 ? t + std::log1p(std::exp(-t)) : std::log1p(std::exp(t)); }

} // namespace

double LogisticModel::probability(const std::vector<double>& x) const
{
    double t = intercept;
    for (std::size_t j = 0; j < weights.size(); ++j) t += weights[j] * (x[j] - mean[j]) / scale[j];
    return sigmoid(t);
}

nlohmann::json LogisticModel::toJson() const
{
    return {{"schema", "voxhap.assessment-model/1"}, {"kind", "logistic-regression"}, {"features", features},
        {"mean", mean}, {"scale", scale}, {"weights", weights}, {"intercept", intercept}, {"lambda", lambda},
        {"iterations", iterations},
        {"model", "P(label 1) = 1/(1 + exp(-(intercept + sum_j weights_j*(x_j - mean_j)/scale_j)))"}};
}

LogisticModel LogisticModel::fromJson(const nlohmann::json& j, const std::string& origin)
{
    const auto need = [&](const char* key) -> const nlohmann::json& {
        if (!j.is_object() || !j.contains(key)) throw ValueError(origin + ": " + key + ": missing");
        return j.at(key);
    };
    if (need("schema") != "voxhap.assessment-model/1")
        throw ValueError(origin + ": schema: must be \"voxhap.assessment-model/1\"");
    if (need("kind") != "logistic-regression") throw ValueError(origin + ": kind: must be \"logistic-regression\"");
    LogisticModel m;
    const auto numbers = [&](const char* key) {
        const nlohmann::json& a = need(key);
        std::vector<double> v;
        if (!a.is_array()) throw ValueError(origin + ": " + key + ": must be a list of numbers");
        for (const auto& x : a) {
            if (!x.is_number() || !std::isfinite(x.get<double>()))
                throw ValueError(origin + ": " + key + ": must be a list of finite numbers");
            v.push_back(x.get<double>());
        }
        return v;
    };
    const nlohmann::json& f = need("features");
    if (!f.is_array() || f.empty()) throw ValueError(origin + ": features: must be a non-empty list of names");
    for (const auto& n : f) {
        if (!n.is_string()) throw ValueError(origin + ": features: must be a list of names");
        m.features.push_back(n.get<std::string>());
    }
    m.mean = numbers("mean");
    m.scale = numbers("scale");
    m.weights = numbers("weights");
    const std::size_t n = m.features.size();
    if (m.mean.size() != n || m.scale.size() != n || m.weights.size() != n)
        throw ValueError(
            origin + ": mean, scale and weights must have one value per feature (" + std::to_string(n) + ")");
    for (double s : m.scale) {
        if (!(s > 0)) throw ValueError(origin + ": scale: must be positive");
    }
    const nlohmann::json& b = need("intercept");
    if (!b.is_number() || !std::isfinite(b.get<double>()))
        throw ValueError(origin + ": intercept: must be a finite number");
    m.intercept = b.get<double>();
    if (j.contains("lambda") && j.at("lambda").is_number()) m.lambda = j.at("lambda").get<double>();
    return m;
}

LogisticModel trainLogistic(const LabelledSet& data, const TrainOptions& o)
{
    const std::size_t n = data.x.size(), p = data.features.size();
    if (n == 0 || data.y.size() != n) throw ValueError(data.origin + ": no labelled samples to train on");
    const long positives = std::count(data.y.begin(), data.y.end(), 1);
    if (positives == 0 || positives == long(n))
        throw ValueError(data.origin + ": label: both classes (0 and 1) are needed to train");
    if (!(o.lambda >= 0) || !std::isfinite(o.lambda)) throw ValueError("lambda: must be a finite number >= 0");
    LogisticModel m;
    m.features = data.features;
    m.lambda = o.lambda;
    m.mean.assign(p, 0.0);
    m.scale.assign(p, 1.0);
    m.weights.assign(p, 0.0);
    // Standardise; constant features (sd 0) stay out of the fit with weight 0.
    std::vector<std::size_t> active;
    for (std::size_t j = 0; j < p; ++j) {
        if (data.x.size() && data.x[0].size() != p) throw ValueError(data.origin + ": rows and features disagree");
        double s = 0, s2 = 0;
        for (const auto& row : data.x) s += row[j];
        m.mean[j] = s / double(n);
        for (const auto& row : data.x) s2 += (row[j] - m.mean[j]) * (row[j] - m.mean[j]);
        const double sd = std::sqrt(s2 / double(n));
        if (sd > 0 && std::isfinite(sd)) {
            m.scale[j] = sd;
            active.push_back(j);
        }
    }
    const Eigen::Index k = Eigen::Index(active.size()) + 1;
    Eigen::MatrixXd z(Eigen::Index(n), k);
    Eigen::VectorXd y(static_cast<Eigen::Index>(n));
    for (std::size_t i = 0; i < n; ++i) {
        z(Eigen::Index(i), 0) = 1.0;
        for (std::size_t a = 0; a < active.size(); ++a)
            z(Eigen::Index(i), Eigen::Index(a) + 1) = (data.x[i][active[a]] - m.mean[active[a]]) / m.scale[active[a]];
        y(Eigen::Index(i)) = data.y[i];
    }
    Eigen::VectorXd penalty = Eigen::VectorXd::Constant(k, o.lambda);
    penalty(0) = 0.0; // the intercept is not penalised
    const auto loss = [&](const Eigen::VectorXd& beta) {
        const Eigen::VectorXd t = z * beta;
        double l = 0;
        for (Eigen::Index i = 0; i < t.size(); ++i) l += softplus(t(i)) - y(i) * t(i);
        return l + 0.5 * (penalty.array() * beta.array().square()).sum();
    };
    // Start at the intercept-only optimum: logit of the positive fraction.
    Eigen::VectorXd beta = Eigen::VectorXd::Zero(k);
    const double frac = double(positives) / double(n);
    beta(0) = std::log(frac / (1.0 - frac));
    double current = loss(beta);
    bool converged = false;
    int it = 0;
    for (; it < o.maxIterations && !converged; ++it) {
        const Eigen::VectorXd t = z * beta;
        Eigen::VectorXd pr(t.size()), w(t.size());
        for (Eigen::Index i = 0; i < t.size(); ++i) {
            pr(i) = sigmoid(t(i));
            w(i) = pr(i) * (1.0 - pr(i));
        }
        const Eigen::VectorXd grad = z.transpose() * (pr - y) + penalty.cwiseProduct(beta);
        Eigen::MatrixXd h = z.transpose() * w.asDiagonal() * z;
        h.diagonal() += penalty;
        const Eigen::VectorXd step = h.ldlt().solve(grad);
        if (!step.allFinite()) break;
        // Backtracking: halve the step until the loss does not rise (convex loss).
        double s = 1.0;
        Eigen::VectorXd next = beta - step;
        double l = loss(next);
        while (l > current + 1e-12 * std::abs(current) && s > 1e-10) {
            s *= 0.5;
            next = beta - s * step;
            l = loss(next);
        }
        converged = (s * step).cwiseAbs().maxCoeff() < o.tolerance;
        beta = next;
        current = l;
    }
    // On separable classes the unpenalised likelihood has no maximum: the weights run
    // off until the fitted probabilities round to 0 and 1, where the gradient vanishes
    // numerically. A standardised weight of 25 already means odds of e^25 (1e11) per
    // standard deviation; a real optimum is never there [chosen].
    constexpr double kRunawayWeight = 25.0;
    if (converged && k > 1 && beta.tail(k - 1).cwiseAbs().maxCoeff() > kRunawayWeight) converged = false;
    if (!converged || !beta.allFinite()) {
        throw ValueError(data.origin + ": the logistic fit did not converge in " + std::to_string(o.maxIterations) +
            " Newton steps, or its weights ran off to infinity" +
            (o.lambda == 0 ? " (with lambda 0 the classes are likely separable: give lambda > 0)" : ""));
    }
    m.iterations = it;
    m.intercept = beta(0);
    for (std::size_t a = 0; a < active.size(); ++a) m.weights[active[a]] = beta(Eigen::Index(a) + 1);
    return m;
}

Interval wilsonInterval(std::int64_t successes, std::int64_t n, double z)
{
    if (n <= 0) return {0.0, 1.0};
    const double nn = double(n), ph = double(successes) / nn, z2 = z * z;
    const double denom = 1.0 + z2 / nn;
    const double centre = (ph + z2 / (2.0 * nn)) / denom;
    const double half = z / denom * std::sqrt(ph * (1.0 - ph) / nn + z2 / (4.0 * nn * nn));
    return {std::max(0.0, centre - half), std::min(1.0, centre + half)};
}

CrossValidation crossValidate(const LabelledSet& data, int folds, const TrainOptions& o, unsigned seed)
{
    const std::size_t n = data.x.size();
    if (folds < 2 || std::size_t(folds) > n)
        throw ValueError(data.origin + ": folds: must be in [2, " + std::to_string(n) + "] (the number of samples)");
    std::vector<std::size_t> byClass[2];
    for (std::size_t i = 0; i < n; ++i) byClass[data.y[i]].push_back(i);
    for (int c = 0; c < 2; ++c) {
        if (byClass[c].size() < 2)
            throw ValueError(data.origin + ": label: class " + std::to_string(c) +
                " has fewer than 2 samples: too few to cross-validate");
    }
    std::mt19937 rng(seed);
    std::vector<int> foldOf(n, 0);
    int next = 0;
    for (auto& members : byClass) {
        std::shuffle(members.begin(), members.end(), rng);
        for (std::size_t i : members) foldOf[i] = next++ % folds;
    }
    CrossValidation cv;
    cv.folds = folds;
    cv.n = std::int64_t(n);
    cv.predicted.assign(n, -1);
    for (int f = 0; f < folds; ++f) {
        LabelledSet train;
        train.features = data.features;
        train.origin = data.origin + " (fold " + std::to_string(f + 1) + ")";
        for (std::size_t i = 0; i < n; ++i) {
            if (foldOf[i] == f) continue;
            train.x.push_back(data.x[i]);
            train.y.push_back(data.y[i]);
        }
        const LogisticModel m = trainLogistic(train, o);
        for (std::size_t i = 0; i < n; ++i) {
            if (foldOf[i] != f) continue;
            cv.predicted[i] = m.predict(data.x[i]);
            cv.correct += cv.predicted[i] == data.y[i];
        }
    }
    cv.accuracy = double(cv.correct) / double(n);
    cv.ci95 = wilsonInterval(cv.correct, cv.n);
    return cv;
}

} // namespace voxhap::assessment
