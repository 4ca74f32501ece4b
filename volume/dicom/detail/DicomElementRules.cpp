// SPDX-License-Identifier: Apache-2.0
/// @file DicomElementRules.cpp
/// @brief Each rule below mirrors one assertion of GDCM 3.0's ImageHelper
/// (gdcmImageHelper.cxx: ComputeZSpacingFromIPP, GetSpacingValueFromSequence,
/// GetInterceptSlopeValueFromSequence, GetUltraSoundSpacingValueFromSequence).

#include "volume/dicom/detail/DicomElementRules.h"

#include "core/Errors.h"

#include <gdcmAttribute.h>
#include <gdcmDataSet.h>
#include <gdcmImageHelper.h>
#include <gdcmSequenceOfItems.h>

#include <cstdio>
#include <optional>
#include <string>
#include <vector>

namespace voxhap::volume {

namespace {

const gdcm::Tag kShared(0x5200, 0x9229), kPerFrame(0x5200, 0x9230);
const gdcm::Tag kPlanePosition(0x0020, 0x9113), kPlaneOrientation(0x0020, 0x9116);
const gdcm::Tag kPixelMeasures(0x0028, 0x9110), kPixelValueTransformation(0x0028, 0x9145);
const gdcm::Tag kOrientation(0x0020, 0x0037), kPosition(0x0020, 0x0032);
const gdcm::Tag kUltrasoundRegions(0x0018, 0x6011);

std::string tagText(const gdcm::Tag& t)
{
    char buf[16];
    std::snprintf(buf, sizeof buf, "(%04X,%04X)", t.GetGroup(), t.GetElement());
    return buf;
}

[[noreturn]] void fail(
    const std::filesystem::path& file, const gdcm::Tag& t, const std::string& name, const std::string& what)
{
    throw IoError(file.string() + ": " + tagText(t) + " " + name + ": " + what);
}

/// Number of backslash-separated values of a text element (0 when empty).
std::size_t valueCount(const gdcm::DataElement& de)
{
    const gdcm::ByteValue* bv = de.GetByteValue();
    if (!bv || bv->GetLength() == 0) return 0;
    std::size_t n = 1;
    for (std::size_t i = 0; i < bv->GetLength(); ++i) n += bv->GetPointer()[i] == '\\';
    return n;
}

/// The sequence @p tag of @p ds when present; GDCM asserts when it is present
/// but not a sequence, or is read as item 1 while empty.
gdcm::SmartPointer<gdcm::SequenceOfItems> sequence(
    const gdcm::DataSet& ds, const gdcm::Tag& tag, const std::string& name, const std::filesystem::path& file)
{
    if (!ds.FindDataElement(tag)) return nullptr;
    gdcm::SmartPointer<gdcm::SequenceOfItems> sq = ds.GetDataElement(tag).GetValueAsSQ();
    if (!sq) fail(file, tag, name, "is not a sequence");
    if (sq->GetNumberOfItems() == 0) fail(file, tag, name, "is an empty sequence");
    return sq;
}

/// The values of @p tag in @p ds, which must hold exactly @p count numbers.
template <std::uint16_t G, std::uint16_t E>
std::optional<std::vector<double>> numbers(
    const gdcm::DataSet& ds, std::size_t count, const std::string& name, const std::filesystem::path& file)
{
    const gdcm::Tag tag(G, E);
    if (!ds.FindDataElement(tag)) return std::nullopt;
    const gdcm::DataElement& de = ds.GetDataElement(tag);
    if (valueCount(de) != count) fail(file, tag, name, "needs " + std::to_string(count) + " values");
    gdcm::Attribute<G, E> at;
    at.SetFromDataElement(de);
    std::vector<double> v;
    for (std::size_t i = 0; i < count; ++i) v.push_back(at.GetValue(static_cast<unsigned int>(i)));
    return v;
}

/// Item 1 of a functional group (shared or per-frame), checked; empty if absent.
const gdcm::DataSet* firstItem(
    const gdcm::DataSet& ds, const gdcm::Tag& group, const std::string& name, const std::filesystem::path& file)
{
    auto sq = sequence(ds, group, name, file);
    return sq ? &sq->GetItem(1).GetNestedDataSet() : nullptr;
}

/// The sequences ImageHelper opens inside a functional-group item.
void checkGroupItem(const gdcm::DataSet& item, const std::filesystem::path& file)
{
    (void)sequence(item, kPlanePosition, "PlanePositionSequence", file);
    (void)sequence(item, kPixelMeasures, "PixelMeasuresSequence", file);
    (void)sequence(item, kPixelValueTransformation, "PixelValueTransformationSequence", file);
    if (auto sq = sequence(item, kPlaneOrientation, "PlaneOrientationSequence", file)) {
        (void)numbers<0x0020, 0x0037>(sq->GetItem(1).GetNestedDataSet(), 6, "ImageOrientationPatient", file);
    }
}

/// Orientation from item 1 of @p group, the way ComputeZSpacingFromIPP looks for it.
std::optional<std::vector<double>> groupOrientation(const gdcm::DataSet* item, const std::filesystem::path& file)
{
    if (!item || !item->FindDataElement(kPlaneOrientation)) return std::nullopt;
    auto sq = sequence(*item, kPlaneOrientation, "PlaneOrientationSequence", file);
    return numbers<0x0020, 0x0037>(sq->GetItem(1).GetNestedDataSet(), 6, "ImageOrientationPatient", file);
}

} // namespace

std::string_view expectedVr(std::uint16_t group, std::uint16_t element)
{
    // The elements ImageHelper and PixmapReader read through gdcm::Attribute,
    // whose SetFromDataElement asserts that the file's VR is the dictionary's
    // (found by fuzz/FuzzDicomPreflight with a DS turned into another VR).
    struct Rule {
        std::uint32_t tag;
        std::string_view vr;
    };
    static constexpr Rule kRules[] = {
        {0x00080016, "UI"},
        {0x00080060, "CS"},
        {0x00180050, "DS"},
        {0x00180088, "DS"},
        {0x00181164, "DS"},
        {0x00182010, "DS"},
        {0x0018602c, "FD"},
        {0x0018602e, "FD"},
        {0x00200032, "DS"},
        {0x00200037, "DS"},
        {0x00280002, "US"},
        {0x00280004, "CS"},
        {0x00280006, "US"},
        {0x00280008, "IS"},
        {0x00280009, "AT"},
        {0x00280010, "US"},
        {0x00280011, "US"},
        {0x00280030, "DS"},
        {0x00280034, "IS"},
        {0x00280100, "US"},
        {0x00280101, "US"},
        {0x00280102, "US"},
        {0x00280103, "US"},
        {0x00281050, "DS"},
        {0x00281051, "DS"},
        {0x00281052, "DS"},
        {0x00281053, "DS"},
        {0x00281054, "LO"},
        {0x00281101, "US|SS"},
        {0x00281102, "US|SS"},
        {0x00281103, "US|SS"},
        {0x30040002, "CS"},
        {0x3004000c, "DS"},
        {0x3004000e, "DS"},
    };
    const std::uint32_t tag = std::uint32_t(group) << 16 | element;
    for (const Rule& r : kRules) {
        if (r.tag == tag) return r.vr;
    }
    return {};
}

bool needsElementRules(const gdcm::DataSet& ds)
{
    return ds.FindDataElement(kShared) || ds.FindDataElement(kPerFrame) || ds.FindDataElement(kUltrasoundRegions);
}

void checkElementRules(const gdcm::DataSet& ds, const std::filesystem::path& file)
{
    // GetUltraSoundSpacingValueFromSequence: a sequence whose first item holds
    // one PhysicalDeltaX and one PhysicalDeltaY.
    if (auto sq = sequence(ds, kUltrasoundRegions, "SequenceOfUltrasoundRegions", file)) {
        const gdcm::DataSet& region = sq->GetItem(1).GetNestedDataSet();
        for (const gdcm::Tag& t : {gdcm::Tag(0x0018, 0x602c), gdcm::Tag(0x0018, 0x602e)}) {
            if (!region.FindDataElement(t) || region.GetDataElement(t).GetVL() != 8) {
                fail(file, t, "PhysicalDelta", "needs one FD value in the first ultrasound region");
            }
        }
    }
    const gdcm::DataSet* shared = firstItem(ds, kShared, "SharedFunctionalGroupsSequence", file);
    const gdcm::DataSet* frame1 = firstItem(ds, kPerFrame, "PerFrameFunctionalGroupsSequence", file);
    if (!shared && !frame1) return;
    if (shared) checkGroupItem(*shared, file);

    // ComputeZSpacingFromIPP: the orientation must be found (shared group,
    // first frame's group, then the top level) ...
    std::optional<std::vector<double>> cosines = groupOrientation(shared, file);
    if (!cosines) cosines = groupOrientation(frame1, file);
    if (!cosines) {
        std::vector<double> top(6);
        if (!gdcm::ImageHelper::GetDirectionCosinesFromDataSet(ds, top)) {
            fail(file, kOrientation, "ImageOrientationPatient", "not in the functional groups nor at the top level");
        }
        cosines = top;
    }
    // ... every frame's plane position is a non-empty sequence, and a frame
    // that states its own orientation states the shared one.
    if (!frame1) return;
    auto frames = sequence(ds, kPerFrame, "PerFrameFunctionalGroupsSequence", file);
    for (gdcm::SequenceOfItems::SizeType i = 1; i <= frames->GetNumberOfItems(); ++i) {
        const gdcm::DataSet& item = frames->GetItem(i).GetNestedDataSet();
        checkGroupItem(item, file);
        auto position = sequence(item, kPlanePosition, "PlanePositionSequence", file);
        if (!position) continue;
        const gdcm::DataSet& plane = position->GetItem(1).GetNestedDataSet();
        (void)numbers<0x0020, 0x0032>(plane, 3, "ImagePositionPatient", file);
        std::vector<double> own(6);
        if (plane.FindDataElement(kOrientation) && gdcm::ImageHelper::GetDirectionCosinesFromDataSet(plane, own) &&
            own != *cosines) {
            fail(file, kOrientation, "ImageOrientationPatient",
                "frame " + std::to_string(i) + " is oriented differently from the others");
        }
    }
}

} // namespace voxhap::volume
