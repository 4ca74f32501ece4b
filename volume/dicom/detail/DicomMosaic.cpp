// SPDX-License-Identifier: Apache-2.0
/// @file DicomMosaic.cpp
/// @brief Mosaic detection and tile geometry from the CSA header (GDCM's
/// CSAHeader and SplitMosaicFilter read it).

#include "volume/dicom/detail/DicomMosaic.h"

#include "core/Errors.h"

#include <Eigen/Geometry>
#include <gdcmCSAHeader.h>
#include <gdcmReader.h>
#include <gdcmSplitMosaicFilter.h>

#include <cmath>
#include <sstream>

namespace voxhap::volume {

bool isMosaic(const DicomHeader& h)
{
    std::stringstream in(h.imageType);
    std::string item;
    while (std::getline(in, item, '\\')) {
        while (!item.empty() && (item.back() == ' ' || item.back() == '\0')) item.pop_back();
        while (!item.empty() && item.front() == ' ') item.erase(item.begin());
        if (item == "MOSAIC") return true;
    }
    return false;
}

void readMosaic(DicomHeader& h)
{
    const std::string name = h.file.string();
    if (h.storedFrames != 1)
        throw IoError(name + ": (0008,0008) ImageType MOSAIC on a multi-frame file: not a Siemens mosaic");
    gdcm::Reader reader;
    reader.SetFileName(name.c_str());
    if (!reader.Read()) throw IoError(name + ": not a readable DICOM file");
    const gdcm::File& file = reader.GetFile();
    // The CSA image header's count (or (0019,100A)); GDCM's fallback guesses
    // from the acquisition matrix and pads with black slices, which voxhap
    // does not accept.
    unsigned images = 0;
    {
        gdcm::CSAHeader csa;
        const gdcm::DataSet& ds = file.GetDataSet();
        const gdcm::PrivateTag& t = gdcm::CSAHeader::GetCSAImageHeaderInfoTag();
        if (ds.FindDataElement(t) && csa.LoadFromDataElement(ds.GetDataElement(t)) &&
            csa.FindCSAElementByName("NumberOfImagesInMosaic")) {
            images = gdcm::SplitMosaicFilter::GetNumberOfImagesInMosaic(file);
        } else {
            const gdcm::PrivateTag vb(0x0019, 0x0a, "SIEMENS MR HEADER");
            if (ds.FindDataElement(vb)) images = gdcm::SplitMosaicFilter::GetNumberOfImagesInMosaic(file);
        }
    }
    if (images == 0 || images > 4096) {
        throw IoError(name +
            ": (0029,1010) CSA NumberOfImagesInMosaic: missing or invalid, so the mosaic cannot be split into its "
            "slices");
    }
    const int side = int(std::ceil(std::sqrt(double(images))));
    if (h.storedColumns % side != 0 || h.storedRows % side != 0) {
        throw IoError(name + ": (0028,0010) Rows / (0028,0011) Columns " + std::to_string(h.storedRows) + "×" +
            std::to_string(h.storedColumns) + " is not " + std::to_string(side) + "×" + std::to_string(side) +
            " tiles of " + std::to_string(images) + " mosaic images");
    }
    gdcm::SplitMosaicFilter filter;
    filter.SetFile(file);
    double snv[3] = {0, 0, 0};
    bool inverted = false;
    if (!filter.ComputeMOSAICSliceNormal(snv, inverted)) {
        throw IoError(name +
            ": (0029,1010) CSA SliceNormalVector: missing or not along ±(row × column), so the order of "
            "the mosaic's slices is unknown");
    }
    const double spacing = h.spacingBetweenSlices.value_or(h.sliceThickness);
    if (!(spacing > 0)) {
        throw IoError(name +
            ": (0018,0088) SpacingBetweenSlices and (0018,0050) SliceThickness: missing, so the mosaic's "
            "slices cannot be placed");
    }
    const int tileRows = h.storedRows / side, tileColumns = h.storedColumns / side;
    const Vec3d normal = Vec3d(snv[0], snv[1], snv[2]).normalized();
    const Vec3d first = h.framePositions.front() +
        h.rowDirection * h.pixelSpacing[1] * double(h.storedColumns - tileColumns) / 2.0 +
        h.columnDirection * h.pixelSpacing[0] * double(h.storedRows - tileRows) / 2.0;
    h.framePositions.clear();
    for (unsigned k = 0; k < images; ++k) h.framePositions.push_back(first + double(k) * spacing * normal);
    h.rows = tileRows;
    h.columns = tileColumns;
    h.frames = int(images);
    h.mosaicImages = int(images);
    h.mosaicTilesPerSide = side;
    // The tiles' positions are computed, not stored: their unit is that of
    // the stored position and spacing, which the floor of the checks covers.
}

} // namespace voxhap::volume
