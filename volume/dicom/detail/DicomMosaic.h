// SPDX-License-Identifier: Apache-2.0
/// @file DicomMosaic.h
/// @brief Siemens mosaic images: the slices of one volume tiled into one
/// stored image (the usual form of Siemens EPI: fMRI, diffusion, perfusion).
///
/// A mosaic of n slices is a square of ⌈√n⌉ × ⌈√n⌉ tiles, filled row by row;
/// the number of slices is in the CSA image header, (0029,1010)
/// NumberOfImagesInMosaic (or (0019,100A) on VB/VE software). Its geometry:
/// - ImagePositionPatient is that of the whole mosaic image as if it were one
///   slice centred where the tiles are, so the first tile's first pixel lies
///   half the size difference further along the row and column directions:
///   p0 = IPP + r̂·Δc·(C − c)/2 + ĉ·Δr·(R − r)/2 (C, R the stored columns and
///   rows; c, r a tile's) — nibabel's MosaicWrapper.image_position, SPM's
///   spm_dicom_convert and dcm2niix all apply this correction;
/// - tile k lies at p0 + k·s·n̂, with n̂ the CSA SliceNormalVector (which may
///   point against r̂ × ĉ) and s SpacingBetweenSlices (0018,0088), else
///   SliceThickness.
/// Without the number of slices or the slice normal the tiles cannot be
/// placed: such a mosaic is refused, never loaded as one big slice.
#pragma once

#include "volume/dicom/DicomHeaders.h"

namespace voxhap::volume {

/// @brief True if @p h's ImageType says MOSAIC (Siemens' marker).
bool isMosaic(const DicomHeader& h);

/// @brief Turn @p h into its tiles: rows, columns and frames become a
/// tile's rows and columns and the number of slices; framePositions the
/// tiles' positions; mosaicImages and mosaicTilesPerSide are set.
/// @throw IoError naming the file and the field that is missing or inconsistent
void readMosaic(DicomHeader& h);

/// @brief Where tile @p k's first pixel lies in the stored image: its row and
/// column offsets [pixels].
inline void mosaicTileOrigin(const DicomHeader& h, int k, int& row, int& column)
{
    row = (k / h.mosaicTilesPerSide) * h.rows;
    column = (k % h.mosaicTilesPerSide) * h.columns;
}

} // namespace voxhap::volume
