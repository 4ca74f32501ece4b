// SPDX-License-Identifier: Apache-2.0
/// @file DicomIdentity.cpp
/// @brief Three elements read with GDCM's selected-tag reader.

#include "volume/dicom/DicomIdentity.h"

#include "core/Errors.h"

#include <gdcmReader.h>
#include <gdcmStringFilter.h>

#include <algorithm>
#include <cctype>
#include <set>

namespace voxhap::volume {

namespace {

std::string trimmed(std::string s)
{
    const auto notSpace = [](unsigned char c) { return !std::isspace(c) && c != '\0'; };
    s.erase(s.begin(), std::find_if(s.begin(), s.end(), notSpace));
    s.erase(std::find_if(s.rbegin(), s.rend(), notSpace).base(), s.end());
    return s;
}

} // namespace

DicomIdentity readDicomIdentity(const std::filesystem::path& file)
{
    const gdcm::Tag name(0x0010, 0x0010), id(0x0010, 0x0020), frame(0x0020, 0x0052);
    gdcm::Reader reader;
    reader.SetFileName(file.string().c_str());
    if (!reader.ReadSelectedTags(std::set<gdcm::Tag>{name, id, frame})) {
        throw IoError(file.string() + ": cannot read its patient and frame-of-reference elements as DICOM");
    }
    gdcm::StringFilter sf;
    sf.SetFile(reader.GetFile());
    const gdcm::DataSet& ds = reader.GetFile().GetDataSet();
    auto value = [&](const gdcm::Tag& t) { return ds.FindDataElement(t) ? trimmed(sf.ToString(t)) : std::string(); };
    return {value(id), value(name), value(frame)};
}

} // namespace voxhap::volume
