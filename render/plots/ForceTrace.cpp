// SPDX-License-Identifier: Apache-2.0
/// @file ForceTrace.cpp
#include "render/plots/ForceTrace.h"

#include "core/BoundedRead.h"

#include "core/Errors.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>

namespace voxhap::render {

namespace fs = std::filesystem;

namespace {

/// A plain comma-separated file with a header line; columns found by name.
class Csv {
public:
    explicit Csv(const fs::path& file) : mFile(file)
    {
        requireRegularFile(file, "recording"); // a FIFO or /dev/zero would never end
        mIn.open(file);
        if (!mIn) throw IoError(file.string() + ": cannot open the recording");
        std::string header;
        if (!readLine(header)) throw ValueError(file.string() + ": line 1: empty file");
        mHeader = split(header);
    }
    bool hasColumn(const std::string& name) const
    {
        return std::find(mHeader.begin(), mHeader.end(), name) != mHeader.end();
    }
    std::size_t column(const std::string& name) const
    {
        const auto it = std::find(mHeader.begin(), mHeader.end(), name);
        if (it == mHeader.end()) throw ValueError(mFile.string() + ": line 1: no column '" + name + "'");
        return std::size_t(it - mHeader.begin());
    }
    /// The next row; false at the end. @throw ValueError on a short row
    bool next()
    {
        std::string line;
        do {
            ++mLine;
            if (!readLine(line)) return false;
        } while (line.rfind('#', 0) == 0); // a comment: session.csv's closing line states its counts
        mRow = split(line);
        if (mRow.size() < mHeader.size()) {
            throw ValueError(mFile.string() + ": line " + std::to_string(mLine) + ": " + std::to_string(mRow.size()) +
                " fields, the header has " + std::to_string(mHeader.size()));
        }
        return true;
    }
    const std::string& text(std::size_t c) const { return mRow[c]; }
    double number(std::size_t c) const
    {
        const std::string& s = mRow[c];
        double x = 0;
        const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), x);
        if (ec != std::errc() || end != s.data() + s.size() || !std::isfinite(x)) {
            throw ValueError(
                mFile.string() + ": line " + std::to_string(mLine) + ": " + mHeader[c] + ": not a finite number");
        }
        return x;
    }

private:
    /// A line of at most kMaxLineBytes: a file without line breaks is refused, not
    /// read whole into one string. A recording's rows are about 150 bytes.
    static constexpr std::size_t kMaxLineBytes = 65536;
    bool readLine(std::string& line)
    {
        line.clear();
        for (int c; (c = mIn.get()) != std::char_traits<char>::eof();) {
            if (c == '\n') return true;
            if (line.size() == kMaxLineBytes) {
                throw ValueError(mFile.string() + ": line " + std::to_string(mLine) + ": longer than " +
                    std::to_string(kMaxLineBytes) + " bytes");
            }
            line.push_back(char(c));
        }
        return !line.empty();
    }
    static std::vector<std::string> split(const std::string& line)
    {
        std::vector<std::string> out;
        std::size_t start = 0;
        while (true) {
            const std::size_t comma = line.find(',', start);
            out.push_back(line.substr(start, comma == std::string::npos ? std::string::npos : comma - start));
            if (comma == std::string::npos) break;
            start = comma + 1;
        }
        if (!out.empty() && !out.back().empty() && out.back().back() == '\r') out.back().pop_back();
        return out;
    }

    fs::path mFile;
    std::ifstream mIn;
    std::vector<std::string> mHeader, mRow;
    int mLine = 1;
};

/// Layer bands from where the tip was: runs of one layer name along the
/// samples; a layer met again (the needle drawn back and pushed on) widens its band.
class BandBuilder {
public:
    void add(double depthMm, const std::string& layer)
    {
        if (layer.empty() || layer == "air") {
            mCurrent.reset();
            return;
        }
        if (!mCurrent || mBands[*mCurrent].name != layer) {
            const auto it = std::find_if(mBands.begin(), mBands.end(), [&](const auto& b) { return b.name == layer; });
            if (it == mBands.end()) {
                mBands.push_back({layer, depthMm, depthMm});
                mCurrent = mBands.size() - 1;
            } else {
                mCurrent = std::size_t(it - mBands.begin());
            }
        }
        ForceTrace::Band& b = mBands[*mCurrent];
        b.startMm = std::min(b.startMm, depthMm), b.endMm = std::max(b.endMm, depthMm);
    }
    std::vector<ForceTrace::Band> take() { return std::move(mBands); }

private:
    std::vector<ForceTrace::Band> mBands;
    std::optional<std::size_t> mCurrent;
};

ForceTrace readInsertionCsv(const fs::path& file)
{
    Csv csv(file);
    const std::size_t depth = csv.column("depth_mm"), force = csv.column("force_N"),
                      axial = csv.column("axial_model_N"), plunger = csv.column("plunger_N"),
                      layer = csv.column("layer"), events = csv.column("events");
    ForceTrace t;
    t.title = file.parent_path().filename().string() + ": insertion";
    BandBuilder bands;
    while (csv.next()) {
        const double d = csv.number(depth);
        t.samples.push_back({d, csv.number(force), csv.number(axial), csv.number(plunger)});
        bands.add(d, csv.text(layer));
        const std::string& names = csv.text(events);
        for (std::size_t start = 0; start < names.size();) {
            const std::size_t semi = std::min(names.find(';', start), names.size());
            t.addEvent(d, names.substr(start, semi - start));
            start = semi + 1;
        }
    }
    t.layers = bands.take();
    return t;
}

ForceTrace readSessionCsv(const fs::path& file)
{
    Csv csv(file);
    const std::size_t depth = csv.column("depth_mm"), axial = csv.column("axial_N"), plunger = csv.column("plunger_N"),
                      layer = csv.column("layer");
    const std::size_t f[3] = {csv.column("fx_N"), csv.column("fy_N"), csv.column("fz_N")};
    ForceTrace t;
    t.title = file.parent_path().filename().string() + ": session";
    BandBuilder bands;
    while (csv.next()) {
        const double d = csv.number(depth);
        const double fx = csv.number(f[0]), fy = csv.number(f[1]), fz = csv.number(f[2]);
        t.samples.push_back({d, std::sqrt(fx * fx + fy * fy + fz * fz), csv.number(axial), csv.number(plunger)});
        bands.add(d, csv.text(layer));
    }
    t.layers = bands.take();
    const fs::path eventsFile = file.parent_path() / "events.csv";
    if (fs::exists(eventsFile)) {
        Csv ev(eventsFile);
        const std::size_t at = ev.column("depth_mm"), name = ev.column("event");
        while (ev.next()) t.addEvent(ev.number(at), ev.text(name));
    }
    return t;
}

} // namespace

void ForceTrace::addEvent(double depthMm, const std::string& name)
{
    if (name.empty() || name == "skin_contact" || name == "critical_clear") return;
    if (!events.empty() && std::abs(events.back().depthMm - depthMm) < 1e-9)
        events.back().text += ", " + name;
    else
        events.push_back({depthMm, name});
}

ForceTrace forceTrace(
    const haptic::InsertionResult& r, const std::vector<haptic::Layer>& layers, const std::string& title)
{
    ForceTrace t;
    t.title = title;
    t.samples.reserve(r.rows.size());
    for (const haptic::InsertionRow& row : r.rows)
        t.samples.push_back({row.depthMm, row.force.norm(), row.axialN, row.plungerN});
    for (const haptic::Layer& l : layers) {
        if (l.role != haptic::LayerRole::Air) t.layers.push_back({l.name, l.startMm, l.endMm});
    }
    for (const haptic::Event& e : r.events) t.addEvent(e.depthMm, haptic::eventName(e.type));
    return t;
}

ForceTrace readForceTrace(const fs::path& path)
{
    fs::path file = path;
    if (fs::is_directory(path)) {
        if (fs::exists(path / "insertion.csv"))
            file = path / "insertion.csv";
        else if (fs::exists(path / "session.csv"))
            file = path / "session.csv";
        else
            throw IoError(path.string() + ": no insertion.csv or session.csv in the folder");
    }
    const Csv probe(file);
    if (probe.hasColumn("tip_x_mm")) return readSessionCsv(file);
    if (probe.hasColumn("axial_model_N")) return readInsertionCsv(file);
    throw ValueError(
        file.string() + ": line 1: neither an insertion.csv (voxhap simulate) nor a session.csv (voxhap serve)");
}

} // namespace voxhap::render
