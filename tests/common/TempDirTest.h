// SPDX-License-Identifier: Apache-2.0
/// @file TempDirTest.h
/// @brief A test fixture with its own scratch directory (mDir), named after the
/// process and the test so that parallel CTest runs never share one, and
/// removed afterwards.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <unistd.h>

namespace voxhap::test {

class TempDirTest : public testing::Test {
protected:
    void SetUp() override
    {
        const auto* info = testing::UnitTest::GetInstance()->current_test_info();
        mDir = std::filesystem::temp_directory_path() /
            ("voxhap-" + std::string(info->test_suite_name()) + "-" + std::to_string(::getpid()) + "-" + info->name());
        std::filesystem::create_directories(mDir);
    }
    void TearDown() override
    {
        std::error_code ignored;
        std::filesystem::remove_all(mDir, ignored);
    }
    std::filesystem::path mDir;
};

/// @brief Expect @p load(path) to throw an Error whose one-line message names the
/// file and contains @p field.
template <typename Error, typename Load>
void expectRefused(Load&& load, const std::filesystem::path& p, const std::string& field)
{
    try {
        load(p);
        ADD_FAILURE() << p << " loaded; expected an error about " << field;
    } catch (const Error& e) {
        const std::string msg = e.what();
        EXPECT_NE(msg.find(p.filename().string()), std::string::npos) << msg;
        EXPECT_NE(msg.find(field), std::string::npos) << msg;
        EXPECT_EQ(msg.find('\n'), std::string::npos) << "one line: " << msg;
    }
}

} // namespace voxhap::test
