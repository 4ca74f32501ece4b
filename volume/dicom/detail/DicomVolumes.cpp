// SPDX-License-Identifier: Apache-2.0
/// @file DicomVolumes.cpp
/// @brief Grouping by separating key, then by repeated positions in acquisition order.

#include "volume/dicom/detail/DicomVolumes.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>
#include <tuple>

namespace voxhap::volume {

namespace {

/// Acquisition order of a slice: (AcquisitionNumber, TriggerTime, InstanceNumber, file, frame).
using Order = std::tuple<long, double, long, std::size_t, int>;

Order orderOf(const DicomSlice& s, const std::vector<DicomHeader>& headers)
{
    const DicomFrameKey& k = headers[s.file].frameKey(s.frame);
    return {
        k.acquisitionNumber.value_or(0), k.triggerTime.value_or(0.0), k.instanceNumber.value_or(0), s.file, s.frame};
}

std::string shortNumber(double v)
{
    std::ostringstream os;
    os << v;
    return os.str();
}

/// Two headers describe the same slice grid: orientation, size and pixel spacing
/// (what checkSameGrid requires of the slices of one volume).
bool sameGrid(const DicomHeader& a, const DicomHeader& b)
{
    constexpr double kDirection = 1e-4, kSpacingMm = 1e-4;
    return a.rows == b.rows && a.columns == b.columns && (a.rowDirection - b.rowDirection).norm() < kDirection &&
        (a.columnDirection - b.columnDirection).norm() < kDirection &&
        std::abs(a.pixelSpacing[0] - b.pixelSpacing[0]) < kSpacingMm &&
        std::abs(a.pixelSpacing[1] - b.pixelSpacing[1]) < kSpacingMm;
}

/// A group of CT slices that may join another of a different image type (rule 1's exception).
struct CtRun {
    std::string key;       ///< the group's separating key
    std::string otherKeys; ///< the separating key without the image type: only equal ones join
    const DicomHeader* grid = nullptr;
    std::vector<double> along; ///< positions along the normal, ascending
    double thickness = 0;      ///< (0018,0050), else the median step [mm]
    std::string types;         ///< the image types in the run, for the volume's label
};

/// Join the CT groups of @p groups that differ in image type alone, share one grid,
/// hold distinct positions and whose ranges along the normal follow each other,
/// overlapping by at most the thinner one's slice thickness. Returns what was
/// joined ("A (4 mm) and B (7 mm)"); @p typeLabel gets the joined groups' label.
std::string joinCtImageTypes(std::map<std::string, std::vector<std::size_t>>& groups,
    const std::vector<DicomSlice>& slices, const std::vector<DicomHeader>& headers, double toleranceMm,
    std::map<std::string, std::string>& typeLabel)
{
    std::vector<CtRun> runs;
    for (const auto& [key, members] : groups) {
        const DicomHeader& h0 = headers[slices[members.front()].file];
        bool ok = true;
        for (std::size_t i : members) {
            const DicomHeader& h = headers[slices[i].file];
            ok = ok && h.modality == "CT" && sameGrid(h0, h);
        }
        if (!ok) continue;
        CtRun r;
        r.key = key;
        DicomFrameKey k = h0.frameKey(slices[members.front()].frame);
        r.types = k.imageType;
        k.imageType.clear();
        r.otherKeys = k.separating();
        r.grid = &h0;
        const Vec3d normal = h0.rowDirection.cross(h0.columnDirection).normalized();
        for (std::size_t i : members) r.along.push_back(slices[i].position.dot(normal));
        std::sort(r.along.begin(), r.along.end());
        std::vector<double> steps;
        for (std::size_t i = 1; i < r.along.size(); ++i) steps.push_back(r.along[i] - r.along[i - 1]);
        if (!steps.empty() && *std::min_element(steps.begin(), steps.end()) <= toleranceMm) continue; // repeats
        std::sort(steps.begin(), steps.end());
        r.thickness = h0.sliceThickness > 0 ? h0.sliceThickness : steps.empty() ? 0.0 : steps[steps.size() / 2];
        if (!(r.thickness > 0)) continue;
        r.types += " (" + shortNumber(r.thickness) + " mm)";
        runs.push_back(std::move(r));
    }
    std::sort(
        runs.begin(), runs.end(), [](const CtRun& a, const CtRun& b) { return a.along.front() < b.along.front(); });
    std::string joined;
    std::vector<bool> taken(runs.size(), false);
    for (std::size_t a = 0; a < runs.size(); ++a) {
        if (taken[a]) continue;
        CtRun& head = runs[a];
        std::string types = head.types;
        double thinnest = head.thickness;
        for (std::size_t b = a + 1; b < runs.size(); ++b) {
            const CtRun& next = runs[b];
            if (taken[b] || next.otherKeys != head.otherKeys || !sameGrid(*head.grid, *next.grid)) continue;
            const double overlap = head.along.back() - next.along.front();
            const double thickness = std::min(head.thickness, next.thickness);
            // Follows: starts after the head's start, ends past its end, overlaps by at most a slice.
            if (!(next.along.front() > head.along.front() && next.along.back() > head.along.back() &&
                    overlap <= thickness + toleranceMm))
                continue;
            std::vector<double> all = head.along;
            all.insert(all.end(), next.along.begin(), next.along.end());
            std::sort(all.begin(), all.end());
            bool distinct = true;
            for (std::size_t i = 1; i < all.size(); ++i) distinct = distinct && all[i] - all[i - 1] > toleranceMm;
            if (!distinct) continue; // a slice of each at one position: not one stack
            auto& into = groups[head.key];
            const auto& from = groups[next.key];
            into.insert(into.end(), from.begin(), from.end());
            groups.erase(next.key);
            head.along = std::move(all);
            types += " and " + next.types;
            thinnest = std::min(thinnest, next.thickness);
            head.thickness = thinnest;
            taken[b] = true;
        }
        if (types != head.types) {
            typeLabel[head.key] = types;
            joined += (joined.empty() ? "" : "; ") + types;
        }
    }
    return joined;
}

} // namespace

std::vector<DicomSlice> seriesSlices(const std::vector<DicomHeader>& headers)
{
    std::vector<DicomSlice> slices;
    for (std::size_t f = 0; f < headers.size(); ++f) {
        const DicomHeader& h = headers[f];
        for (int k = 0; k < h.frames; ++k) {
            DicomSlice s;
            s.file = f;
            s.frame = k;
            s.position = h.framePositions[std::size_t(k)];
            s.slope = h.frameRescale.empty() ? h.slope : h.frameRescale[std::size_t(k)].first;
            s.intercept = h.frameRescale.empty() ? h.intercept : h.frameRescale[std::size_t(k)].second;
            slices.push_back(s);
        }
    }
    return slices;
}

std::string DicomVolumeSet::shape() const
{
    std::ostringstream os;
    std::set<std::size_t> sizes;
    for (const auto& v : volumes) sizes.insert(v.size());
    if (volumes.size() == 1) {
        os << "1 volume of " << volumes.front().size() << " slices";
    } else if (sizes.size() == 1) {
        os << volumes.size() << " volumes × " << *sizes.begin() << " slices";
    } else {
        os << volumes.size() << " volumes of ";
        for (std::size_t v = 0; v < volumes.size(); ++v) {
            if (v > 0) os << (v + 1 == volumes.size() ? " and " : ", ");
            os << volumes[v].size();
        }
        os << " slices";
    }
    return os.str();
}

std::string DicomVolumeSet::summary() const
{
    std::ostringstream os;
    for (std::size_t v = 0; v < labels.size();) {
        std::size_t end = v + 1;
        while (end < labels.size() && labels[end] == labels[v]) ++end;
        if (v > 0) os << ", ";
        os << v + 1;
        if (end - v > 1) os << "–" << end;
        if (!labels[v].empty()) os << ": " << labels[v];
        v = end;
    }
    return os.str();
}

DicomVolumeSet splitVolumes(
    const std::vector<DicomSlice>& slices, const std::vector<DicomHeader>& headers, double toleranceMm)
{
    DicomVolumeSet out;
    // 1. Separating keys.
    std::map<std::string, std::vector<std::size_t>> groups;
    for (std::size_t i = 0; i < slices.size(); ++i) {
        groups[headers[slices[i].file].frameKey(slices[i].frame).separating()].push_back(i);
    }
    // 1b. CT image types whose ranges follow each other along the normal: one stack.
    std::map<std::string, std::string> typeLabel;
    out.joined = joinCtImageTypes(groups, slices, headers, toleranceMm, typeLabel);
    // Which key fields differ between the groups: they name the volumes.
    bool byType = false, byEcho = false, byTime = false, byB = false, byStack = false, byRepeat = false;
    const std::size_t s0 = groups.begin()->second.front(); // a slice of a group that remains
    const DicomFrameKey& k0 = headers[slices[s0].file].frameKey(slices[s0].frame);
    for (const auto& [key, members] : groups) {
        const DicomFrameKey& k = headers[slices[members.front()].file].frameKey(slices[members.front()].frame);
        byType |= k.imageType != k0.imageType;
        byEcho |= k.echoNumber != k0.echoNumber || (k.echoTime.has_value() != k0.echoTime.has_value()) ||
            (k.echoTime && k0.echoTime && std::lround(*k.echoTime * 100) != std::lround(*k0.echoTime * 100));
        byTime |= k.temporalPosition != k0.temporalPosition;
        byB |= (k.bValue.has_value() != k0.bValue.has_value()) ||
            (k.bValue && k0.bValue && std::lround(*k.bValue) != std::lround(*k0.bValue));
        byStack |= k.stack != k0.stack;
    }

    struct SeriesVolume {
        std::vector<std::size_t> members;
        /// Time point, echo number, echo time, stack: the volumes' natural
        /// order where the headers number them; acquisition order otherwise.
        std::tuple<long, long, long, long> index{0, 0, 0, 0};
        Order first;
        std::string label;
    };
    std::vector<SeriesVolume> volumes;
    for (auto& [key, members] : groups) {
        // 2. Repeated positions within a group: cluster along the group's own
        // normal (a localizer in a CT series lies in another plane than the
        // axial slices, and its image type keeps it in a group of its own).
        const DicomHeader& h0 = headers[slices[members.front()].file];
        const Vec3d groupNormal = h0.rowDirection.cross(h0.columnDirection).normalized();
        const Vec3d& normal = groupNormal;
        std::vector<std::size_t> byPosition = members;
        std::sort(byPosition.begin(), byPosition.end(), [&](std::size_t a, std::size_t b) {
            return slices[a].position.dot(normal) < slices[b].position.dot(normal);
        });
        std::vector<std::vector<std::size_t>> clusters;
        double last = 0;
        for (std::size_t i : byPosition) {
            const double along = slices[i].position.dot(normal);
            if (clusters.empty() || along - last > toleranceMm) clusters.emplace_back();
            clusters.back().push_back(i);
            last = along;
        }
        std::size_t lo = slices.size(), hi = 0;
        for (const auto& c : clusters) lo = std::min(lo, c.size()), hi = std::max(hi, c.size());
        const DicomFrameKey& k = headers[slices[members.front()].file].frameKey(slices[members.front()].frame);
        std::ostringstream label;
        const auto sep = [&label] { return label.tellp() == 0 ? "" : ", "; };
        if (byB) label << sep() << "b=" << (k.bValue ? shortNumber(std::round(*k.bValue)) : std::string("?"));
        if (byEcho) {
            label << sep() << "echo " << (k.echoNumber ? std::to_string(*k.echoNumber) : std::string("?"));
            if (k.echoTime) label << " (TE " << shortNumber(*k.echoTime) << " ms)";
        }
        if (byTime)
            label << sep() << "time point "
                  << (k.temporalPosition ? std::to_string(*k.temporalPosition) : std::string("?"));
        if (byStack) label << sep() << "stack " << (k.stack ? std::to_string(*k.stack) : std::string("?"));
        if (byType) label << sep() << (typeLabel.count(key) ? typeLabel.at(key) : k.imageType);
        if (lo != hi) {
            std::ostringstream why;
            why << "slice positions" << (label.tellp() ? " of " + label.str() : std::string()) << " repeat unequally ("
                << lo << " to " << hi << " times): not a regular set of volumes";
            out.problem = why.str();
            return out;
        }
        if (hi > 1) byRepeat = true;
        // The k-th slice of each position, in acquisition order, goes to the k-th volume.
        std::vector<SeriesVolume> repeats(hi);
        for (auto& c : clusters) {
            std::sort(c.begin(), c.end(), [&](std::size_t a, std::size_t b) {
                return orderOf(slices[a], headers) < orderOf(slices[b], headers);
            });
            for (std::size_t r = 0; r < c.size(); ++r) repeats[r].members.push_back(c[r]);
        }
        for (SeriesVolume& v : repeats) {
            v.index = {k.temporalPosition.value_or(0), k.echoNumber.value_or(0),
                std::lround(k.echoTime.value_or(0) * 100), k.stack.value_or(0)};
            v.first = orderOf(slices[v.members.front()], headers);
            for (std::size_t i : v.members) v.first = std::min(v.first, orderOf(slices[i], headers));
            v.label = label.str();
            volumes.push_back(std::move(v));
        }
    }
    std::sort(volumes.begin(), volumes.end(), [](const SeriesVolume& a, const SeriesVolume& b) {
        return std::tie(a.index, a.first) < std::tie(b.index, b.first);
    });
    std::vector<std::string> by;
    if (byType) by.push_back("image type");
    if (byEcho) by.push_back("echo");
    if (byTime) by.push_back("temporal position");
    if (byB) by.push_back("b-value");
    if (byStack) by.push_back("stack");
    if (byRepeat) by.push_back("acquisition order");
    for (std::size_t i = 0; i < by.size(); ++i) out.separatedBy += (i ? ", " : "") + by[i];
    for (SeriesVolume& v : volumes) {
        out.volumes.push_back(std::move(v.members));
        out.labels.push_back(v.label);
    }
    return out;
}

} // namespace voxhap::volume
