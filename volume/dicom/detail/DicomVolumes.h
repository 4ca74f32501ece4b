// SPDX-License-Identifier: Apache-2.0
/// @file DicomVolumes.h
/// @brief The 3D volumes inside one DICOM series: fMRI time points,
/// diffusion directions, echoes of a multi-echo or field-map acquisition,
/// stacks and frame types of enhanced objects.
///
/// Slices are split in two steps:
/// 1. Slices that differ in image type, echo number, echo time, temporal
///    position, b-value or stack are never stacked together, even at distinct
///    positions (a two-echo field map whose echoes alternate along the stack
///    must not become one volume). One exception, for CT alone: groups that
///    differ in image type only, on one grid, each at distinct positions, are
///    one stack when their ranges along the normal follow each other,
///    overlapping by at most one slice thickness (the thinner group's). A head
///    CT of 4 mm slices marked ADD over the posterior fossa and 7 mm slices
///    above is one CT of one head in calibrated HU; two reconstructions of the
///    same range (thin and thick over the same slab) stay separate volumes, and
///    so does every MR split.
/// 2. Within one such group, a position that occurs m times means m volumes:
///    each position's slices are taken in acquisition order (AcquisitionNumber,
///    then TriggerTime, then InstanceNumber, then file order) and the k-th
///    goes to volume k. Positions that occur unequally often cannot be split:
///    the series is refused, naming the counts.
/// Volumes are numbered from 1 by temporal position, echo and stack where the
/// headers give them, then in acquisition order (the earliest slice of each),
/// which puts a diffusion series' b = 0 first.
#pragma once

#include "core/Math.h"
#include "volume/dicom/DicomHeaders.h"

#include <cstddef>
#include <string>
#include <vector>

namespace voxhap::volume {

/// @brief One 2D slice of a series: a frame of a file or a tile of a mosaic.
struct DicomSlice {
    std::size_t file = 0; ///< index into the series' headers
    int frame = 0;        ///< frame in the file, or tile of a mosaic
    Vec3d position{0, 0, 0};
    double slope = 1, intercept = 0;
};

/// @brief The volumes of a series.
struct DicomVolumeSet {
    std::vector<std::vector<std::size_t>> volumes; ///< indices into the slices, one list per volume
    std::vector<std::string> labels;               ///< one per volume: "b=1000", "echo 2 (TE 7.38 ms)", ...
    std::string separatedBy;                       ///< "b-value, acquisition order"; empty for one volume
    /// CT image types stacked as one volume (rule 1's exception): "ORIGINAL\PRIMARY\AXIAL\ADD (4 mm) and
    /// ORIGINAL\PRIMARY\AXIAL (7 mm)"; empty when none were joined.
    std::string joined;
    std::string problem; ///< why the slices form no regular set of volumes; empty if they do

    std::size_t count() const { return volumes.size(); }
    /// @brief "13 volumes × 25 slices" or "2 volumes of 17 and 19 slices".
    std::string shape() const;
    /// @brief The labels compacted for one line: "1: b=0, 2–13: b=1000".
    std::string summary() const;
};

/// @brief The slices of every frame of @p headers, in file order.
std::vector<DicomSlice> seriesSlices(const std::vector<DicomHeader>& headers);

/// @brief Split @p slices into volumes (the rule above). Positions are
/// compared along each group's own slice normal.
/// @param toleranceMm   positions closer than this along the normal are the same position
DicomVolumeSet splitVolumes(
    const std::vector<DicomSlice>& slices, const std::vector<DicomHeader>& headers, double toleranceMm);

} // namespace voxhap::volume
