// SPDX-License-Identifier: Apache-2.0
/// @file TestLabelledCsv.cpp
/// @brief labelled.csv (assessment/LabelledCsv.h): what the reader takes and
/// refuses, naming the line and the column, and what the writer writes reads
/// back to the same numbers.

#include "assessment/LabelledCsv.h"
#include "core/Errors.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace voxhap::assessment {
namespace {

TEST(LabelledCsv, ReadsAndRefusesNamingLineAndColumn)
{
    const LabelledSet d =
        parseLabelledCsv("# a comment\nsession,label,speed,success\na,0,1.5,true\nb,1,6,false\n", "l.csv");
    ASSERT_EQ(d.features, (std::vector<std::string>{"speed", "success"}));
    EXPECT_EQ(d.y, (std::vector<int>{0, 1}));
    EXPECT_EQ(d.x[1], (std::vector<double>{6.0, 0.0}));
    EXPECT_EQ(d.ids[0], "a");
    const auto refused = [](const std::string& text, const std::string& what) {
        try {
            parseLabelledCsv(text, "l.csv");
            ADD_FAILURE() << "accepted: " << text;
        } catch (const ValueError& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    refused("speed,success\n1,2\n", "l.csv: line 1: no 'label' column");
    refused("label,speed\n2,1\n", "l.csv: line 2: column 'label': '2' is not 0 or 1");
    refused("label,speed\n1,fast\n", "l.csv: line 2: column 'speed': 'fast' is not a number");
    refused("label,speed\n1\n", "l.csv: line 2: 1 cells, the header has 2");
}

TEST(LabelledCsv, WhatTheWriterWritesReadsBackToTheSameNumbers)
{
    // Values as metrics.json holds them: a count, a real that needs 17 digits, a flag.
    const nlohmann::json a = {{"pops", 3}, {"speed_mean_mm_per_s", 0.1 + 0.2}, {"success", true}, {"other", "x"}};
    const nlohmann::json b = {{"pops", 0}, {"speed_mean_mm_per_s", 12.5}, {"success", false}};
    const std::vector<std::string> columns{"pops", "speed_mean_mm_per_s", "success"};
    const std::string text = labelledCsvText({{"careful-1", 0, a}, {"reckless-1", 1, b}}, columns, "a cohort");
    EXPECT_EQ(text.rfind("# a cohort\nsession,label,pops,speed_mean_mm_per_s,success\ncareful-1,0,3,", 0), 0u) << text;
    const LabelledSet d = parseLabelledCsv(text, "l.csv");
    EXPECT_EQ(d.features, columns);
    EXPECT_EQ(d.ids, (std::vector<std::string>{"careful-1", "reckless-1"}));
    EXPECT_EQ(d.y, (std::vector<int>{0, 1}));
    // Exactly the JSON's numbers: 0.1 + 0.2 is not 0.3 in doubles, and must stay so.
    EXPECT_EQ(d.x[0], (std::vector<double>{3.0, 0.1 + 0.2, 1.0}));
    EXPECT_NE(d.x[0][1], 0.3);
    EXPECT_EQ(d.x[1], (std::vector<double>{0.0, 12.5, 0.0}));

    const auto refused = [&](std::vector<LabelledRow> rows, const std::vector<std::string>& cols, const char* what) {
        try {
            labelledCsvText(rows, cols, "");
            ADD_FAILURE() << "written: " << what;
        } catch (const ValueError& e) {
            EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
        }
    };
    refused({{"a,b", 0, a}}, columns, "session 'a,b': an id holds a comma");
    refused({{"a", 2, a}}, columns, "session a: label 2 is not 0 or 1");
    refused({{"b", 1, b}}, {"other"}, "session b: other: not a number or a flag"); // missing
    refused({{"a", 0, a}}, {"other"}, "session a: other: not a number or a flag"); // text
    refused({{"a", 0, {{"pops", nullptr}}}}, {"pops"}, "session a: pops: not a number or a flag");
}

} // namespace
} // namespace voxhap::assessment
