// SPDX-License-Identifier: Apache-2.0
/// @file LabelledCsv.cpp
/// @brief labelled.csv read and written.
#include "assessment/LabelledCsv.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <optional>
#include <sstream>

namespace voxhap::assessment {

namespace {

std::string trim(const std::string& s)
{
    const auto b = s.find_first_not_of(" \t\r");
    if (b == std::string::npos) return "";
    return s.substr(b, s.find_last_not_of(" \t\r") - b + 1);
}

std::vector<std::string> splitCsv(const std::string& line)
{
    std::vector<std::string> out;
    std::stringstream in(line);
    for (std::string f; std::getline(in, f, ',');) out.push_back(trim(f));
    if (!line.empty() && line.back() == ',') out.push_back("");
    return out;
}

/// A number, or true/false as 1/0; nullopt otherwise.
std::optional<double> cell(const std::string& s)
{
    if (s == "true") return 1.0;
    if (s == "false") return 0.0;
    if (s.empty()) return std::nullopt;
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size() || !std::isfinite(v)) return std::nullopt;
    return v;
}

/// A cell or a header name that the reader would split or cut.
bool breaksCsv(const std::string& s) { return s.find_first_of(",\r\n") != std::string::npos; }

} // namespace

LabelledSet parseLabelledCsv(const std::string& text, const std::string& origin)
{
    LabelledSet d;
    d.origin = origin;
    std::stringstream in(text);
    std::vector<std::string> header;
    int labelCol = -1, idCol = -1, lineNo = 0;
    for (std::string line; std::getline(in, line);) {
        ++lineNo;
        const std::string t = trim(line);
        if (t.empty() || t[0] == '#') continue;
        const std::vector<std::string> cells = splitCsv(t);
        const std::string where = origin + ": line " + std::to_string(lineNo);
        if (header.empty()) {
            header = cells;
            for (int c = 0; c < int(header.size()); ++c) {
                const std::string& h = header[std::size_t(c)];
                if (h.empty()) throw ValueError(where + ": column " + std::to_string(c + 1) + ": empty column name");
                if (std::count(header.begin(), header.end(), h) > 1)
                    throw ValueError(where + ": column '" + h + "': named twice");
                if (h == "label")
                    labelCol = c;
                else if (h == "session")
                    idCol = c;
                else
                    d.features.push_back(h);
            }
            if (labelCol < 0) throw ValueError(where + ": no 'label' column (0 or 1 per session)");
            if (d.features.empty()) throw ValueError(where + ": no feature columns beside 'label'");
            continue;
        }
        if (cells.size() != header.size())
            throw ValueError(where + ": " + std::to_string(cells.size()) + " cells, the header has " +
                std::to_string(header.size()));
        std::vector<double> row;
        for (int c = 0; c < int(cells.size()); ++c) {
            const std::string& h = header[std::size_t(c)];
            if (c == idCol) continue;
            const std::optional<double> v = cell(cells[std::size_t(c)]);
            if (c == labelCol) {
                if (!v || (*v != 0.0 && *v != 1.0))
                    throw ValueError(where + ": column 'label': '" + cells[std::size_t(c)] + "' is not 0 or 1");
                d.y.push_back(int(*v));
            } else {
                if (!v)
                    throw ValueError(where + ": column '" + h + "': '" + cells[std::size_t(c)] + "' is not a number");
                row.push_back(*v);
            }
        }
        d.x.push_back(std::move(row));
        d.ids.push_back(idCol >= 0 ? cells[std::size_t(idCol)] : "row " + std::to_string(lineNo));
    }
    if (header.empty()) throw ValueError(origin + ": empty: expected a header line and labelled rows");
    if (d.x.empty()) throw ValueError(origin + ": no rows after the header");
    return d;
}

LabelledSet readLabelledCsv(const std::filesystem::path& file)
{
    return parseLabelledCsv(readBoundedFile(file, "labelled CSV"), file.string());
}

std::string labelledCsvText(
    const std::vector<LabelledRow>& rows, const std::vector<std::string>& columns, const std::string& comment)
{
    std::ostringstream csv;
    if (!comment.empty()) csv << "# " << comment << '\n';
    csv << "session,label";
    for (const auto& c : columns) {
        if (breaksCsv(c)) throw ValueError("labelled CSV: column '" + c + "': a name holds a comma or line break");
        csv << ',' << c;
    }
    csv << '\n';
    for (const LabelledRow& r : rows) {
        if (breaksCsv(r.session))
            throw ValueError("labelled CSV: session '" + r.session + "': an id holds a comma or line break");
        if (r.label != 0 && r.label != 1)
            throw ValueError(
                "labelled CSV: session " + r.session + ": label " + std::to_string(r.label) + " is not 0 or 1");
        csv << r.session << ',' << r.label;
        for (const auto& c : columns) {
            const nlohmann::json* v = r.metrics.contains(c) ? &r.metrics.at(c) : nullptr;
            if (!v || !(v->is_boolean() || v->is_number()))
                throw ValueError("labelled CSV: session " + r.session + ": " + c + ": not a number or a flag");
            // As metrics.json holds it: the reader reads the same number back.
            csv << ',' << (v->is_boolean() ? (v->get<bool>() ? "1" : "0") : v->dump());
        }
        csv << '\n';
    }
    return csv.str();
}

} // namespace voxhap::assessment
