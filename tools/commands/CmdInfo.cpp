// SPDX-License-Identifier: Apache-2.0
/// @file CmdInfo.cpp
/// @brief `voxhap info <file>`: describe a volume (.vdb, NIfTI, NRRD,
/// MetaImage or a DICOM folder). On DICOM it first prints the series table
/// and the files set aside, so that a user sees what is there even when the
/// default series cannot be loaded.

#include "tools/Cli.h"
#include "tools/InfoReport.h"
#include "tools/LoadOptions.h"

#include "core/BoundedRead.h"
#include "core/Errors.h"
#include "volume/VolumeFile.h"

#include <iomanip>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>

namespace voxhap::tools {

namespace {

struct InfoOptions {
    CommonOptions common;
    ReaderOptions reader;
    bool verbose = false;
    std::string file;
};

std::string spacingText(const Vec3d& s)
{
    std::ostringstream os;
    os << std::setprecision(4) << s.x() << " x " << s.y() << " x ";
    if (s.z() > 0)
        os << s.z();
    else
        os << "?";
    os << " mm";
    return os.str();
}

nlohmann::json seriesJson(const std::vector<volume::DicomSeriesInfo>& all)
{
    nlohmann::json list = nlohmann::json::array();
    for (const auto& s : all) {
        nlohmann::json j = {{"index", s.index}, {"uid", s.uid}, {"number", s.number}, {"modality", s.modality},
            {"description", s.description}, {"rows", s.rows}, {"columns", s.columns}, {"slices", s.slices},
            {"files", s.files.size()}, {"orientation", s.orientation},
            {"spacing_mm", {s.spacing.x(), s.spacing.y(), s.spacing.z()}}, {"volumes", s.volumes},
            {"volume_shape", s.volumeShape}, {"loadable", s.problem.empty()}};
        if (s.volumes > 1) {
            j["volumes_by"] = s.separatedBy;
            j["volume_labels"] = s.volumeSummary;
        }
        if (!s.weighting.empty()) j["mr_weighting"] = s.weighting, j["mr_weighting_reason"] = s.weightingReason;
        if (s.damagedFiles) j["damaged_files"] = s.damagedFiles;
        if (!s.problem.empty()) j["problem"] = s.problem;
        list.push_back(j);
    }
    return list;
}

nlohmann::json skippedJson(const std::vector<volume::DicomSkippedFile>& skipped)
{
    nlohmann::json counts = nlohmann::json::object(), files = nlohmann::json::array();
    for (const auto& s : skipped) {
        counts[s.category] = counts.value(s.category, 0) + 1;
        files.push_back({{"file", s.file.string()}, {"category", s.category}, {"reason", s.reason}});
    }
    return {{"counts", counts}, {"files", files}};
}

void printSeriesTable(std::ostream& os, const volume::DicomCatalog& c, const std::string& loadedUid)
{
    os << "DICOM series (choose with --series UID, SeriesNumber or #index; * loaded):\n";
    os << "  " << std::left << std::setw(5) << "#" << std::setw(8) << "number" << std::setw(5) << "mod" << std::setw(13)
       << "size" << std::setw(18) << "volumes" << std::setw(19) << "orientation" << std::setw(28) << "spacing"
       << "description\n";
    for (const auto& s : c.series) {
        std::ostringstream size, vols;
        size << s.columns << 'x' << s.rows << 'x' << s.slices;
        if (s.volumes > 1)
            vols << s.volumes << " x " << (s.slices / std::int64_t(s.volumes)) << " sl";
        else if (s.volumes == 1)
            vols << "1";
        else
            vols << "?";
        os << (s.uid == loadedUid ? "* " : "  ") << std::left << std::setw(5) << s.index << std::setw(8)
           << (s.number.empty() ? "-" : s.number) << std::setw(5) << s.modality << std::setw(13) << size.str()
           << std::setw(18) << vols.str() << std::setw(19) << s.orientation << std::setw(28) << spacingText(s.spacing)
           << s.description << (s.weighting.empty() ? "" : " [" + s.weighting + "]") << '\n';
        os << "        uid " << s.uid << ", " << s.files.size() << " file(s)\n";
        if (s.volumes > 1) os << "        volumes by " << s.separatedBy << ": " << s.volumeSummary << '\n';
        if (!s.problem.empty() && s.uid != loadedUid) os << "        not loaded as is: " << s.problem << '\n';
    }
}

void printSkipped(std::ostream& os, const std::vector<volume::DicomSkippedFile>& skipped, bool verbose)
{
    if (skipped.empty()) return;
    std::map<std::string, int> counts;
    for (const auto& s : skipped) ++counts[s.category];
    os << "set aside " << skipped.size() << " file(s):";
    bool first = true;
    for (const auto& [category, n] : counts) os << (first ? " " : ", ") << n << ' ' << category, first = false;
    os << (verbose ? "\n" : " (names and reasons with --verbose)\n");
    if (verbose) {
        for (const auto& s : skipped) os << "  " << s.reason << '\n';
    }
}

int run(const InfoOptions& o)
{
    const volume::TissueTable& table = tissueTable(o.common);
    // A FIFO or a device (/dev/zero) is refused before formatOf() opens it to look for DICOM.
    requireRegularFile(o.file, "volume", /*allowDirectory=*/true);
    const bool dicom = volume::formatOf(o.file) == volume::VolumeFormat::Dicom;
    const volume::LoadOptions options = loadOptions(o.reader, false);
    std::optional<volume::DicomCatalog> catalog;
    if (dicom) catalog = volume::catalogDicom({o.file}, options.dicom);

    volume::DicomLoadReport report;
    std::optional<volume::Volume> v;
    std::string failure;
    try {
        v = loadVolumeWithProgress(o.file, o.reader, stderrIsTerminal() && !o.common.json, &report);
    } catch (const Error& e) {
        if (!catalog || catalog->series.empty()) throw;
        failure = e.what(); // the table is still worth showing
    }
    if (o.common.json) {
        nlohmann::json j = v ? infoJson(volume::describe(*v, table), o.file) : nlohmann::json::object();
        if (catalog) {
            j["dicom_series"] = seriesJson(catalog->series);
            j["dicom_skipped"] = skippedJson(catalog->skipped);
            if (v) {
                j["dicom_loaded_series"] = report.series.uid;
                j["dicom_chosen_because"] = report.chosenBecause;
                if (report.volume) j["dicom_volume"] = report.volume;
                if (!report.skippedBad.empty()) j["dicom_skipped_bad"] = skippedJson(report.skippedBad);
                j["load_seconds"] = report.seconds;
            }
        }
        if (!failure.empty()) j["error"] = failure;
        std::cout << j.dump(2) << '\n';
        if (!failure.empty()) throw IoError(failure);
        return 0;
    }
    if (catalog) {
        printSeriesTable(std::cout, *catalog, v ? report.series.uid : std::string());
        printSkipped(std::cout, catalog->skipped, o.verbose);
        if (v) {
            std::cout << "loaded #" << report.series.index
                      << (report.volume ? ", volume " + std::to_string(report.volume) : "") << ": "
                      << report.chosenBecause << '\n';
            if (!report.skippedBad.empty()) {
                std::cout << "left out " << report.skippedBad.size()
                          << " unreadable file(s) of the series (--skip-bad):\n";
                for (const auto& s : report.skippedBad) std::cout << "  " << s.reason << '\n';
            }
            if (report.paddedFiles) {
                std::cout << report.paddedFiles << " file(s) carry zero padding after their last element (accepted)\n";
            }
        }
        std::cout << '\n';
    }
    if (!failure.empty()) throw IoError(failure);
    printInfo(std::cout, volume::describe(*v, table), o.file);
    return 0;
}

} // namespace

Action registerInfo(CLI::App& app)
{
    auto o = std::make_shared<InfoOptions>();
    CLI::App* cmd = app.add_subcommand("info",
        "Describe a volume: grids, geometry, sparsity, memory, values, labels, layers; "
        "on DICOM, the series table and the files set aside");
    cmd->add_option("file", o->file, "Volume: a DICOM directory or file, .nii/.nii.gz, .nrrd, .mha/.mhd or .vdb")
        ->required();
    cmd->add_flag("--verbose", o->verbose, "DICOM: name every file set aside, with its reason");
    addReaderOptions(*cmd, o->reader);
    addCommonOptions(*cmd, o->common);
    return [o] { return run(*o); };
}

} // namespace voxhap::tools
