// SPDX-License-Identifier: Apache-2.0
/// @file FuzzInsertionScript.cpp
/// @brief libFuzzer target: the insertion-script CSV reader
/// (InsertionScript::load, `voxhap simulate --script`). Besides "no crash" and
/// the refusal convention, an accepted script is checked: at least two knots,
/// the first at t = 0, times strictly increasing, every number finite; one knot
/// per data line (empty lines, # comments and a header line aside); depth and
/// speed finite everywhere, the depth between its knots' depths; and written
/// back at full precision it reads back to the same knots.

#include "FuzzInput.h"

#include "haptic/scene/ScriptedInsertion.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <string_view>

namespace {

using voxhap::fuzz::finding;
using voxhap::haptic::InsertionScript;

/// The data lines of the file as the script format defines them.
std::size_t dataLines(std::string_view text)
{
    std::size_t count = 0, n = 0;
    while (!text.empty()) {
        const std::size_t end = text.find('\n');
        const std::string_view line = text.substr(0, end);
        text = end == std::string_view::npos ? std::string_view{} : text.substr(end + 1);
        ++n;
        const bool header =
            n == 1 && !line.empty() && !std::isdigit(static_cast<unsigned char>(line[0])) && line[0] != '-';
        if (!line.empty() && line[0] != '#' && !header) ++count;
    }
    return count;
}

void checkScript(const InsertionScript& s, std::string_view text)
{
    const auto& k = s.knots;
    if (k.size() < 2) finding("fewer than two knots");
    if (k.size() != dataLines(text)) finding("knots and data lines differ in number");
    if (k.front().first != 0.0) finding("the first knot is not at t = 0");
    for (std::size_t i = 0; i < k.size(); ++i) {
        if (!std::isfinite(k[i].first) || !std::isfinite(k[i].second)) finding("a knot is not finite");
        if (i > 0 && !(k[i].first > k[i - 1].first)) finding("times do not increase");
    }
    if (s.duration() != k.back().first) finding("the duration is not the last knot's time");
    for (std::size_t i = 1; i < k.size(); ++i) {
        const auto [t0, d0] = k[i - 1];
        const auto [t1, d1] = k[i];
        const double tol = 1e-12 * (std::abs(d0) + std::abs(d1));
        for (const double t : {t0 + 0.25 * (t1 - t0), t0 + 0.5 * (t1 - t0), t1}) {
            const double d = s.depthAt(t), v = s.speedAt(t);
            if (!std::isfinite(d) || !std::isfinite(v))
                finding("depth or speed not finite at t = " + std::to_string(t));
            if (d < std::min(d0, d1) - tol || d > std::max(d0, d1) + tol)
                finding("depth outside its knots' depths at t = " + std::to_string(t));
        }
        if (std::abs(s.depthAt(t1) - d1) > tol) finding("depth at a knot is not the knot's depth");
    }
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    static voxhap::fuzz::ScratchFile scratch(".csv"), rewritten("-rewritten.csv");
    const auto& file = scratch.write(data, size);
    InsertionScript s;
    try {
        s = InsertionScript::load(file);
    } catch (const voxhap::Error& e) {
        voxhap::fuzz::checkRefusal(e, file.string());
        return 0;
    }
    checkScript(s, std::string_view(reinterpret_cast<const char*>(data), size));

    // Round trip: 17 significant digits write every double exactly.
    std::string text = "t_s,depth_mm\n";
    char row[64];
    for (const auto& [t, d] : s.knots) {
        std::snprintf(row, sizeof row, "%.17g,%.17g\n", t, d);
        text += row;
    }
    const auto& again = rewritten.write(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
    InsertionScript back;
    try {
        back = InsertionScript::load(again);
    } catch (const voxhap::Error& e) {
        finding(std::string("the script written back is refused: ") + e.what());
    }
    if (back.knots != s.knots) finding("the script written back reads differently");
    return 0;
}
