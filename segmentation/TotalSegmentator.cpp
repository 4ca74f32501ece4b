// SPDX-License-Identifier: Apache-2.0
/// @file TotalSegmentator.cpp
/// @brief TotalSegmentator v2 `total` classes to voxhap tissues, and its output read back.

#include "segmentation/TotalSegmentator.h"

#include "core/Errors.h"
#include "volume/Grids.h"
#include "volume/VolumeFile.h"

#include <openvdb/openvdb.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <system_error>

namespace voxhap::segmentation {

namespace fs = std::filesystem;

const std::vector<TotalSegmentatorClass>& totalSegmentatorClasses()
{
    // Ids and names: class_map["total"] of totalsegmentator/map_to_binary.py
    // (wasserth/TotalSegmentator, commit 0275d30). The tissue of each [chosen]:
    // organs the table has (lung, kidney, aorta, the new oesophagus and vein,
    // spinal cord, muscle) by name; arteries are arterial blood, the table's aorta;
    // the heart and its appendage, blood-filled and to be avoided, likewise; other
    // viscera, the brain and costal cartilage are soft_tissue; bones are bone with
    // the CT's cortex kept; the trachea keeps what the CT numbers say (its lumen is air).
    static const std::vector<TotalSegmentatorClass> c{
        {1, "spleen", "soft_tissue"},
        {2, "kidney_right", "kidney"},
        {3, "kidney_left", "kidney"},
        {4, "gallbladder", "soft_tissue"},
        {5, "liver", "soft_tissue"},
        {6, "stomach", "soft_tissue"},
        {7, "pancreas", "soft_tissue"},
        {8, "adrenal_gland_right", "soft_tissue"},
        {9, "adrenal_gland_left", "soft_tissue"},
        {10, "lung_upper_lobe_left", "lung"},
        {11, "lung_lower_lobe_left", "lung"},
        {12, "lung_upper_lobe_right", "lung"},
        {13, "lung_middle_lobe_right", "lung"},
        {14, "lung_lower_lobe_right", "lung"},
        {15, "esophagus", "oesophagus"},
        {16, "trachea", ""},
        {17, "thyroid_gland", "soft_tissue"},
        {18, "small_bowel", "soft_tissue"},
        {19, "duodenum", "soft_tissue"},
        {20, "colon", "soft_tissue"},
        {21, "urinary_bladder", "soft_tissue"},
        {22, "prostate", "soft_tissue"},
        {23, "kidney_cyst_left", "kidney"},
        {24, "kidney_cyst_right", "kidney"},
        {25, "sacrum", "bone"},
        {26, "vertebrae_S1", "bone"},
        {27, "vertebrae_L5", "bone"},
        {28, "vertebrae_L4", "bone"},
        {29, "vertebrae_L3", "bone"},
        {30, "vertebrae_L2", "bone"},
        {31, "vertebrae_L1", "bone"},
        {32, "vertebrae_T12", "bone"},
        {33, "vertebrae_T11", "bone"},
        {34, "vertebrae_T10", "bone"},
        {35, "vertebrae_T9", "bone"},
        {36, "vertebrae_T8", "bone"},
        {37, "vertebrae_T7", "bone"},
        {38, "vertebrae_T6", "bone"},
        {39, "vertebrae_T5", "bone"},
        {40, "vertebrae_T4", "bone"},
        {41, "vertebrae_T3", "bone"},
        {42, "vertebrae_T2", "bone"},
        {43, "vertebrae_T1", "bone"},
        {44, "vertebrae_C7", "bone"},
        {45, "vertebrae_C6", "bone"},
        {46, "vertebrae_C5", "bone"},
        {47, "vertebrae_C4", "bone"},
        {48, "vertebrae_C3", "bone"},
        {49, "vertebrae_C2", "bone"},
        {50, "vertebrae_C1", "bone"},
        {51, "heart", "aorta"},
        {52, "aorta", "aorta"},
        {53, "pulmonary_vein", "vein"},
        {54, "brachiocephalic_trunk", "aorta"},
        {55, "subclavian_artery_right", "aorta"},
        {56, "subclavian_artery_left", "aorta"},
        {57, "common_carotid_artery_right", "aorta"},
        {58, "common_carotid_artery_left", "aorta"},
        {59, "brachiocephalic_vein_left", "vein"},
        {60, "brachiocephalic_vein_right", "vein"},
        {61, "atrial_appendage_left", "aorta"},
        {62, "superior_vena_cava", "vein"},
        {63, "inferior_vena_cava", "vein"},
        {64, "portal_vein_and_splenic_vein", "vein"},
        {65, "iliac_artery_left", "aorta"},
        {66, "iliac_artery_right", "aorta"},
        {67, "iliac_vena_left", "vein"},
        {68, "iliac_vena_right", "vein"},
        {69, "humerus_left", "bone"},
        {70, "humerus_right", "bone"},
        {71, "scapula_left", "bone"},
        {72, "scapula_right", "bone"},
        {73, "clavicula_left", "bone"},
        {74, "clavicula_right", "bone"},
        {75, "femur_left", "bone"},
        {76, "femur_right", "bone"},
        {77, "hip_left", "bone"},
        {78, "hip_right", "bone"},
        {79, "spinal_cord", "spinal_cord"},
        {80, "gluteus_maximus_left", "muscle"},
        {81, "gluteus_maximus_right", "muscle"},
        {82, "gluteus_medius_left", "muscle"},
        {83, "gluteus_medius_right", "muscle"},
        {84, "gluteus_minimus_left", "muscle"},
        {85, "gluteus_minimus_right", "muscle"},
        {86, "autochthon_left", "muscle"},
        {87, "autochthon_right", "muscle"},
        {88, "iliopsoas_left", "muscle"},
        {89, "iliopsoas_right", "muscle"},
        {90, "brain", "soft_tissue"},
        {91, "skull", "bone"},
        {92, "rib_left_1", "bone"},
        {93, "rib_left_2", "bone"},
        {94, "rib_left_3", "bone"},
        {95, "rib_left_4", "bone"},
        {96, "rib_left_5", "bone"},
        {97, "rib_left_6", "bone"},
        {98, "rib_left_7", "bone"},
        {99, "rib_left_8", "bone"},
        {100, "rib_left_9", "bone"},
        {101, "rib_left_10", "bone"},
        {102, "rib_left_11", "bone"},
        {103, "rib_left_12", "bone"},
        {104, "rib_right_1", "bone"},
        {105, "rib_right_2", "bone"},
        {106, "rib_right_3", "bone"},
        {107, "rib_right_4", "bone"},
        {108, "rib_right_5", "bone"},
        {109, "rib_right_6", "bone"},
        {110, "rib_right_7", "bone"},
        {111, "rib_right_8", "bone"},
        {112, "rib_right_9", "bone"},
        {113, "rib_right_10", "bone"},
        {114, "rib_right_11", "bone"},
        {115, "rib_right_12", "bone"},
        {116, "sternum", "bone"},
        {117, "costal_cartilages", "soft_tissue"},
    };
    return c;
}

const TotalSegmentatorClass* findTotalSegmentatorClass(const std::string& name)
{
    for (const auto& k : totalSegmentatorClasses()) {
        if (name == k.name) return &k;
    }
    return nullptr;
}

LabelMapping totalSegmentatorMapping(const volume::TissueTable& table)
{
    LabelMapping m;
    m.origin = "the built-in TotalSegmentator v2 'total' mapping";
    const auto id = [&](const std::string& name) {
        const volume::Tissue* t = table.find(name);
        if (!t)
            throw ValueError(table.origin() + ": no tissue '" + name + "', which the TotalSegmentator mapping needs");
        return std::int32_t(t->id);
    };
    for (const auto& k : totalSegmentatorClasses()) {
        const std::string tissue = k.tissue;
        m.tissueOf[k.id] = tissue.empty() ? -1 : id(tissue == "bone" ? "cancellous_bone" : tissue);
    }
    m.keepAutomatic.push_back({id("cancellous_bone"), id("cortical_bone")});
    for (const auto& t : table.tissues()) m.tissueOf[kTissueMaskValue + t.id] = std::int32_t(t.id);
    return m;
}

namespace {

/// "kidney_left.nii.gz" → "kidney_left"; "" when not a NIfTI name.
std::string maskName(const fs::path& p)
{
    const std::string f = p.filename().string();
    for (const std::string ext : {".nii.gz", ".nii"}) {
        if (f.size() > ext.size() && f.compare(f.size() - ext.size(), ext.size(), ext) == 0)
            return f.substr(0, f.size() - ext.size());
    }
    return "";
}

volume::Volume loadPlain(const fs::path& file)
{
    volume::LoadOptions o;
    o.modality = volume::DeclaredModality::Ct; // values into one float grid, whatever they are
    o.dicom.airHu = -1e30f;                    // keep every voxel: 0 is "no label", not air
    return volume::loadVolume(file, o);
}

} // namespace

volume::Volume loadTotalSegmentator(const fs::path& path, const volume::TissueTable& table)
{
    std::error_code ec;
    if (!fs::is_directory(path, ec)) return loadPlain(path);

    // The per-class masks, classes first (by id), then the table's tissues.
    std::vector<std::pair<std::int64_t, fs::path>> masks;
    for (const auto& e : fs::directory_iterator(path, ec)) {
        const std::string name = maskName(e.path());
        if (name.empty()) continue;
        if (const TotalSegmentatorClass* k = findTotalSegmentatorClass(name)) {
            masks.push_back({k->id, e.path()});
        } else if (const volume::Tissue* t = table.find(name)) {
            masks.push_back({kTissueMaskValue + t->id, e.path()});
        } else {
            throw ValueError(e.path().string() + ": '" + name +
                "' is neither a class of TotalSegmentator's total task nor a tissue of the table");
        }
    }
    if (ec) throw IoError(path.string() + ": cannot list the folder (" + ec.message() + ")");
    if (masks.empty()) throw IoError(path.string() + ": no per-class masks (<class>.nii.gz) in this folder");
    std::sort(masks.begin(), masks.end());

    std::unique_ptr<volume::Volume> out;
    volume::LabelGrid::Ptr labels;
    volume::IndexBox box;
    for (const auto& [value, file] : masks) {
        const volume::Volume v = loadPlain(file);
        volume::FloatGrid::ConstPtr g = volume::huGrid(v);
        if (!g) throw ValueError(file.string() + ": the mask holds no grid");
        if (!out) {
            box = v.indexBox();
            out = std::make_unique<volume::Volume>(v.transformPtr()->copy(), box);
            out->metadata() = v.metadata();
            out->metadata().source = path.string();
            labels = volume::LabelGrid::create(volume::kAirLabel);
            labels->setTransform(v.transformPtr()->copy());
        } else if (!(v.indexBox() == box) || !(*v.transformPtr() == *out->transformPtr())) {
            throw ValueError(file.string() + ": geometry: its grid or transform differs from " +
                masks.front().second.filename().string() + "'s (TotalSegmentator writes every mask on one grid)");
        }
        auto acc = labels->getAccessor();
        const bool tissueMask = value >= kTissueMaskValue;
        for (auto it = g->cbeginValueOn(); it; ++it) {
            const float x = *it;
            if (x == 0.0f) continue;
            if (!std::isfinite(x) || x != std::round(x))
                throw ValueError(
                    file.string() + ": data: value " + std::to_string(x) + " is not a mask value (0 or 1)");
            const openvdb::Coord c = it.getCoord();
            // Tissue masks win; among classes the first (lowest id) keeps the voxel.
            if (tissueMask || acc.getValue(c) == volume::kAirLabel) acc.setValue(c, std::int32_t(value));
        }
    }
    out->setGrid(volume::Channel::Label, labels);
    return std::move(*out);
}

} // namespace voxhap::segmentation
