// SPDX-License-Identifier: Apache-2.0
/// @file LabelledCsv.h
/// @brief labelled.csv, the classifier's training set (Classifier.h): its one
/// reader and its one writer. A header line naming the columns; a "label"
/// column of 0/1 (or false/true); an optional "session" column (any text
/// without a comma, an id); every other column a feature, numeric (true/false
/// read as 1/0). Blank lines and lines starting with '#' are skipped. What
/// `voxhap assess --simulate-cohort` writes and `--train` reads.
#pragma once

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace voxhap::assessment {

/// @brief Labelled rows: features by name, label 0 or 1.
struct LabelledSet {
    std::vector<std::string> features;
    std::vector<std::vector<double>> x; ///< one row per sample, features in order
    std::vector<int> y;                 ///< 0 or 1
    std::vector<std::string> ids;       ///< the "session" column, or "row N"
    std::string origin;                 ///< the file, for messages
};

/// @brief Read a labelled CSV: a header line naming the columns; a "label" column
/// of 0/1 (or false/true); an optional "session" column (any text, an id); every
/// other column a feature, numeric (true/false read as 1/0). Blank lines and lines
/// starting with '#' are skipped.
/// @throw IoError, ValueError naming the file, the line and the column
LabelledSet readLabelledCsv(const std::filesystem::path& file);
/// @brief The same from text; @p origin names it in messages.
LabelledSet parseLabelledCsv(const std::string& text, const std::string& origin);

/// @brief One session to write: its id, its label and its metrics.json.
struct LabelledRow {
    std::string session;
    int label = 0; ///< 0 or 1
    nlohmann::json metrics;
};

/// @brief labelled.csv as text: "# @p comment" (when not empty), the header
/// "session,label,<columns>", then one line per row with each column's value as
/// metrics.json holds it (true/false as 1/0); what readLabelledCsv reads back.
/// @throw ValueError naming the session and the column for a value that is
///        missing, null or neither a number nor a flag, a label not 0 or 1, or an
///        id or column name that holds a comma or a line break
std::string labelledCsvText(
    const std::vector<LabelledRow>& rows, const std::vector<std::string>& columns, const std::string& comment);

} // namespace voxhap::assessment
