// SPDX-License-Identifier: Apache-2.0
/// @file Classifier.h
/// @brief A documented, simple classifier of sessions: L2-
/// regularised logistic regression on standardised metrics, fitted by Newton's
/// method, with k-fold cross-validated accuracy and its Wilson 95 % interval.
///
/// Model: P(y = 1 | x) = σ(b + Σ_j w_j·z_j), z_j = (x_j − mean_j)/sd_j, σ(t) = 1/(1 + e^−t),
/// with mean and (population) standard deviation from the training set. The fit
/// minimises −Σ_i [y_i·ln p_i + (1 − y_i)·ln(1 − p_i)] + (λ/2)·Σ_j w_j² (the
/// intercept b is not penalised) by Newton steps with backtracking: the loss is
/// convex, so the minimum is unique. λ > 0 keeps the weights finite when the
/// classes are separable (simulated cohorts often are); λ = 0 is the plain
/// maximum-likelihood fit and is refused when it does not converge. A feature
/// that is constant in the training set gets weight 0.
///
/// The classifier knows only what its labelled training set says. The tests train
/// it on simulated cohorts (careful and reckless simulated hands); nothing here has
/// been trained on or checked against real trainees.
#pragma once

#include "assessment/LabelledCsv.h"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace voxhap::assessment {

struct TrainOptions {
    double lambda = 1.0;      ///< L2 penalty on the standardised weights [chosen: mild for tens of samples]
    int maxIterations = 100;  ///< Newton steps
    double tolerance = 1e-10; ///< on the largest change of a coefficient
};

class LogisticModel {
public:
    std::vector<std::string> features;
    std::vector<double> mean, scale; ///< standardisation of each feature
    std::vector<double> weights;     ///< on the standardised features
    double intercept = 0;
    double lambda = 0;
    int iterations = 0; ///< Newton steps the fit took

    /// @brief P(y = 1 | x), x in the order of @p features.
    double probability(const std::vector<double>& x) const;
    int predict(const std::vector<double>& x) const { return probability(x) >= 0.5 ? 1 : 0; }
    /// @brief {"schema": "voxhap.assessment-model/1", "kind": "logistic-regression", ...}
    nlohmann::json toJson() const;
    /// @throw ValueError naming @p origin and the field
    static LogisticModel fromJson(const nlohmann::json& j, const std::string& origin);
};

/// @brief Fit the model. @throw ValueError when a class is missing, the sizes
/// disagree, or λ = 0 does not converge (separable classes)
LogisticModel trainLogistic(const LabelledSet& data, const TrainOptions& o = {});

/// @brief A 95 % (or other) confidence interval of a proportion.
struct Interval {
    double low = 0, high = 1;
};

/// @brief Wilson score interval of @p successes out of @p n (E. B. Wilson, J. Am.
/// Stat. Assoc. 22, 1927): centre (p̂ + z²/2n)/(1 + z²/n), half-width
/// z/(1 + z²/n)·sqrt(p̂(1 − p̂)/n + z²/4n²); z = 1.959964 for 95 %. [0, 1] for n = 0.
Interval wilsonInterval(std::int64_t successes, std::int64_t n, double z = 1.959963984540054);

struct CrossValidation {
    int folds = 0;
    std::int64_t correct = 0, n = 0;
    double accuracy = 0;
    Interval ci95;
    std::vector<int> predicted; ///< each sample's prediction by the model that did not see it
};

/// @brief Stratified k-fold cross-validation: each class's samples shuffled
/// (mt19937 seeded with @p seed) and dealt to the folds in turn; each fold
/// predicted by a model trained on the others; accuracy over all samples with its
/// Wilson 95 % interval. @throw ValueError when folds ∉ [2, n] or a class has
/// fewer than 2 samples
CrossValidation crossValidate(const LabelledSet& data, int folds, const TrainOptions& o = {}, unsigned seed = 1);

} // namespace voxhap::assessment
