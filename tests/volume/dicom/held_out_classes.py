#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Builds the kinds of DICOM series the reference converter's (dcm2niix)
validation sets cover -- vendors, enhanced and classic objects, transfer
syntaxes, 4D series -- from the real series in ../shared/data, by rewriting
their headers (pydicom) and re-encoding their pixels (DCMTK's dcmconv, dcmcrle,
dcmcjpeg, dcmcjpls; GDCM's gdcmconv for JPEG 2000, which DCMTK lacks).
TestHeldOutDicomClasses.cpp loads each and compares it with what this script
says it must be.

    held_out_classes.py SHARED_DATA OUT_DIR

OUT_DIR/<class>/ holds each series, OUT_DIR/manifest.json the expectations:
per class the folder, what it stands for, "load" or "refuse", the modality,
the number of volumes and what separates them, and for the volume loaded the
reference voxels: OUT_DIR/<class>.raw, float64, the rescaled stored values that
pydicom decodes from the uncompressed source (slices ascending along the
normal, then rows, then columns), with the largest difference the encoding
allows (0 for lossless, NEAR times the slope for near-lossless JPEG-LS) and
the rescaled PixelPaddingValue where one marks pixels that are not tissue.

Every series is cropped to 96 x 96 pixels about the image centre (the
position moved with the crop) and keeps a few slices: small and quick.
"""
import copy
import json
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pydicom
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.sequence import Sequence
from pydicom.uid import ExplicitVRLittleEndian, ImplicitVRLittleEndian, generate_uid

SIZE = 96
PRIVATE_GROUPS_OF = {"siemens": (0x0019, 0x0029, 0x0051), "ge": (0x0009, 0x0019, 0x0021, 0x0023, 0x0025, 0x0027,
                                                                   0x0043, 0x0045)}


def series_files(folder, count, start=0):
    files = sorted(p for p in pathlib.Path(folder).iterdir() if p.is_file())
    return [pydicom.dcmread(str(f)) for f in files[start:start + count]]


def normal_of(ds):
    o = [float(x) for x in ds.ImageOrientationPatient]
    return np.cross(o[:3], o[3:])


def crop(ds, size=SIZE):
    """The centre size x size pixels of ds, its position moved to the crop's first pixel."""
    a = ds.pixel_array
    r0, c0 = (a.shape[0] - size) // 2, (a.shape[1] - size) // 2
    a = np.ascontiguousarray(a[r0:r0 + size, c0:c0 + size])
    o = [float(x) for x in ds.ImageOrientationPatient]
    dr, dc = (float(x) for x in ds.PixelSpacing)  # between rows, between columns
    p = np.array([float(x) for x in ds.ImagePositionPatient])
    p = p + c0 * dc * np.array(o[:3]) + r0 * dr * np.array(o[3:])
    ds.ImagePositionPatient = [f"{x:.6f}" for x in p]
    ds.Rows, ds.Columns = size, size
    ds.PixelData = a.tobytes()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.is_little_endian, ds.is_implicit_VR = True, False
    return ds


def renew(datasets, series_uid=None):
    """A series of its own: new series and instance UIDs."""
    uid = series_uid or generate_uid()
    for k, ds in enumerate(datasets):
        ds.SeriesInstanceUID = uid
        ds.SOPInstanceUID = generate_uid()
        ds.file_meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
        ds.InstanceNumber = k + 1
    return datasets


def strip_private(ds):
    ds.remove_private_tags()
    return ds


def rescaled(ds):
    a = ds.pixel_array.astype(np.float64)
    slope = float(getattr(ds, "RescaleSlope", 1) or 1)
    intercept = float(getattr(ds, "RescaleIntercept", 0) or 0)
    return a * slope + intercept


def write(datasets, folder, implicit=False):
    folder.mkdir(parents=True, exist_ok=True)
    for k, ds in enumerate(datasets):
        ds.file_meta.TransferSyntaxUID = ImplicitVRLittleEndian if implicit else ExplicitVRLittleEndian
        ds.is_little_endian, ds.is_implicit_VR = True, implicit
        ds.save_as(str(folder / f"im{k:03d}.dcm"), write_like_original=False)


def reference(out, name, slices):
    """slices: (position along the normal, 2D rescaled array) of the loaded volume."""
    stack = np.stack([a for _, a in sorted(slices, key=lambda s: s[0])]).astype("<f8")
    stack.tofile(str(out / f"{name}.raw"))
    return list(stack.shape)


def classic(out, manifest, name, stands_for, datasets, modality, weighting=None, implicit=False,
            padding=None):
    datasets = renew([crop(copy.deepcopy(d)) for d in datasets])
    write(datasets, out / name, implicit)
    n = normal_of(datasets[0])
    ref = [(float(np.dot(n, [float(x) for x in d.ImagePositionPatient])), rescaled(d)) for d in datasets]
    manifest.append({"name": name, "stands_for": stands_for, "folder": name, "expect": "load",
                     "modality": modality, "volumes": 1, "load_volume": 0, "weighting": weighting,
                     "shape": reference(out, name, ref), "tolerance": 0.0, "padding": padding})
    return datasets


def transcode(out, manifest, source_name, name, stands_for, command, tolerance=0.0, refusal=None):
    """The series of source_name re-encoded file by file by command (a list; IN and OUT stand for the files);
    with refusal, the loader must refuse each file in one line holding that text."""
    src, dst = out / source_name, out / name
    dst.mkdir()
    for f in sorted(src.iterdir()):
        cmd = [str(f) if c == "IN" else str(dst / f.name) if c == "OUT" else c for c in command]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    shutil.copyfile(out / f"{source_name}.raw", out / f"{name}.raw")
    entry = dict(next(m for m in manifest if m["name"] == source_name))
    entry.update({"name": name, "stands_for": stands_for, "folder": name, "tolerance": tolerance,
                  "transfer_syntax": str(pydicom.dcmread(str(next(dst.iterdir()))).file_meta.TransferSyntaxUID)})
    if refusal:
        entry.update({"expect": "refuse", "refusal": refusal})
    manifest.append(entry)


def enhanced(out, manifest, name, stands_for, datasets, sop_class, modality):
    """The slices as one enhanced multi-frame object: shared pixel measures,
    orientation and rescale, per-frame positions and frame content."""
    slices = [crop(copy.deepcopy(d)) for d in datasets]
    first = slices[0]
    ds = Dataset()
    ds.file_meta = FileMetaDataset()
    ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds.file_meta.MediaStorageSOPClassUID = sop_class
    ds.SOPClassUID = sop_class
    ds.SOPInstanceUID = generate_uid()
    ds.file_meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
    for key in ("PatientName", "PatientID", "StudyInstanceUID", "Manufacturer", "FrameOfReferenceUID",
                "SamplesPerPixel", "PhotometricInterpretation", "BitsAllocated", "BitsStored", "HighBit",
                "PixelRepresentation", "Rows", "Columns", "MagneticFieldStrength"):
        if key in first:
            setattr(ds, key, getattr(first, key))
    ds.Modality = modality
    ds.SeriesInstanceUID = generate_uid()
    ds.ImageType = ["ORIGINAL", "PRIMARY", "AXIAL" if modality == "CT" else "M", "NONE"]
    ds.NumberOfFrames = len(slices)
    shared = Dataset()
    measures = Dataset()
    measures.PixelSpacing = first.PixelSpacing
    measures.SliceThickness = first.get("SliceThickness", 1)
    shared.PixelMeasuresSequence = Sequence([measures])
    orientation = Dataset()
    orientation.ImageOrientationPatient = first.ImageOrientationPatient
    shared.PlaneOrientationSequence = Sequence([orientation])
    transform = Dataset()
    transform.RescaleSlope = first.get("RescaleSlope", 1)
    transform.RescaleIntercept = first.get("RescaleIntercept", 0)
    transform.RescaleType = "HU" if modality == "CT" else "US"
    shared.PixelValueTransformationSequence = Sequence([transform])
    ds.SharedFunctionalGroupsSequence = Sequence([shared])
    frames = []
    for k, s in enumerate(slices):
        f = Dataset()
        pos = Dataset()
        pos.ImagePositionPatient = s.ImagePositionPatient
        f.PlanePositionSequence = Sequence([pos])
        content = Dataset()
        content.InStackPositionNumber = k + 1
        content.StackID = "1"
        f.FrameContentSequence = Sequence([content])
        frames.append(f)
    ds.PerFrameFunctionalGroupsSequence = Sequence(frames)
    ds.PixelData = b"".join(s.pixel_array.tobytes() for s in slices)
    (out / name).mkdir()
    ds.is_little_endian, ds.is_implicit_VR = True, False
    ds.save_as(str(out / name / "enhanced.dcm"), write_like_original=False)
    n = normal_of(first)
    ref = [(float(np.dot(n, [float(x) for x in s.ImagePositionPatient])), rescaled(s)) for s in slices]
    manifest.append({"name": name, "stands_for": stands_for, "folder": name, "expect": "load", "modality": modality,
                     "volumes": 1, "load_volume": 0, "weighting": None, "shape": reference(out, name, ref),
                     "tolerance": 0.0, "padding": None})


def four_d(out, manifest, name, stands_for, datasets, count, tag_volume, separated_by, load_volume):
    """count copies of the slices at the same positions, volume v (from 0) given by tag_volume(ds, v);
    its stored values are the source's plus 7·v, so that the volumes differ."""
    base = [crop(copy.deepcopy(d)) for d in datasets]
    series_uid = generate_uid()
    files, refs = [], {}
    n = normal_of(base[0])
    for v in range(count):
        for s in base:
            d = copy.deepcopy(s)
            a = d.pixel_array.astype(np.int32) + 7 * v
            d.PixelData = a.astype(s.pixel_array.dtype).tobytes()
            tag_volume(d, v)
            d.AcquisitionNumber = v + 1
            files.append(d)
            refs.setdefault(v, []).append((float(np.dot(n, [float(x) for x in d.ImagePositionPatient])), rescaled(d)))
    write(renew(files, series_uid), out / name)
    manifest.append({"name": name, "stands_for": stands_for, "folder": name, "expect": "load",
                     "modality": str(base[0].Modality), "volumes": count, "separated_by": separated_by,
                     "load_volume": load_volume, "weighting": None,
                     "shape": reference(out, name, refs[load_volume - 1]), "tolerance": 0.0, "padding": None})


def private(ds, group, creator, element, vr, value):
    """A private element (group, 0x10xx + element) under its private creator."""
    ds.add_new((group, 0x0010), "LO", creator)
    ds.add_new((group, 0x1000 | element), vr, value)


def main():
    shared, out = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2])
    out.mkdir(parents=True, exist_ok=True)
    manifest = []
    flash = series_files(shared / "mr-dwi-prisma" / "t1-fl2d-sag", 5, 15)
    ge_ct = series_files(shared / "ct-mr-porcine" / "ct", 4, 100)
    ge_mr = series_files(shared / "ct-mr-porcine" / "mr-t2", 4, 45)
    philips_ct = series_files(shared / "ct-abdomen-tcia" / "dicom", 4, 60)

    # Vendors, classic single-frame objects: the real series, and rewritten ones.
    classic(out, manifest, "siemens-mr", "Siemens MR (real: Prisma 2D FLASH)", flash, "MR", "T1-weighted")
    # GE's PixelPaddingValue marks pixels outside the scan: not tissue, made air. In rescaled units.
    ge_padding = float(ge_ct[0].PixelPaddingValue) * float(ge_ct[0].RescaleSlope) + float(ge_ct[0].RescaleIntercept)
    classic(out, manifest, "ge-ct", "GE CT (real: Discovery CT750 HD)", ge_ct, "CT", padding=ge_padding)
    classic(out, manifest, "ge-mr", "GE MR (real: Discovery MR750, T2 spin echo)", ge_mr, "MR", "T2-weighted")
    classic(out, manifest, "philips-ct", "Philips CT (real: TCIA abdomen)", philips_ct, "CT")
    philips_mr = [strip_private(copy.deepcopy(d)) for d in flash]
    for d in philips_mr:
        d.Manufacturer = "Philips Medical Systems"
        d.RescaleSlope, d.RescaleIntercept = "1.5", "0"  # Philips stores a real slope
        private(d, 0x2005, "Philips MR Imaging DD 001", 0x0E, "FL", 0.75)  # the private scale slope, not the DICOM one
    classic(out, manifest, "philips-mr", "Philips MR (the FLASH rewritten: Philips headers, a real rescale slope)",
            philips_mr, "MR", "T1-weighted")
    canon = [copy.deepcopy(d) for d in ge_ct]
    for d in canon:
        for g in PRIVATE_GROUPS_OF["ge"]:
            for e in [e.tag for e in d if e.tag.group == g]:
                del d[e]
        d.Manufacturer = "TOSHIBA"
        d.ManufacturerModelName = "Aquilion ONE"
    classic(out, manifest, "canon-ct", "Canon/Toshiba CT (the GE CT rewritten: Toshiba headers, no GE private tags)",
            canon, "CT", padding=ge_padding)
    agfa = [strip_private(copy.deepcopy(d)) for d in flash]
    for d in agfa:
        d.file_meta.ImplementationVersionName = "AGFA_IMPAX"
    classic(out, manifest, "agfa-mr", "Agfa PACS export (the FLASH: every private element stripped, implicit VR)",
            agfa, "MR", "T1-weighted", implicit=True)

    # Enhanced multi-frame objects.
    enhanced(out, manifest, "enhanced-mr", "Enhanced MR Image Storage (the FLASH as one multi-frame object)", flash,
             "1.2.840.10008.5.1.4.1.1.4.1", "MR")
    enhanced(out, manifest, "enhanced-ct", "Enhanced CT Image Storage (the Philips CT as one multi-frame object)",
             philips_ct, "1.2.840.10008.5.1.4.1.1.2.1", "CT")

    # Transfer syntaxes, on the Philips CT (no padding value to mask).
    src = "philips-ct"
    transcode(out, manifest, src, "ts-implicit", "Implicit VR Little Endian", ["dcmconv", "+ti", "IN", "OUT"])
    transcode(out, manifest, src, "ts-big-endian", "Explicit VR Big Endian (retired)", ["dcmconv", "+tb", "IN", "OUT"])
    transcode(out, manifest, src, "ts-deflated", "Deflated Explicit VR Little Endian", ["dcmconv", "+td", "IN", "OUT"])
    transcode(out, manifest, src, "ts-rle", "RLE Lossless", ["dcmcrle", "IN", "OUT"])
    transcode(out, manifest, src, "ts-jpeg-lossless-sv1", "JPEG Lossless, first-order prediction (process 14 SV1)",
              ["dcmcjpeg", "+e1", "IN", "OUT"])
    transcode(out, manifest, src, "ts-jpeg-lossless", "JPEG Lossless (process 14, other predictors)",
              ["dcmcjpeg", "+el", "IN", "OUT"])
    transcode(out, manifest, src, "ts-jpeg-ls-lossless", "JPEG-LS Lossless", ["dcmcjpls", "+el", "IN", "OUT"])
    slope = float(philips_ct[0].get("RescaleSlope", 1) or 1)
    transcode(out, manifest, src, "ts-jpeg-ls-near-lossless", "JPEG-LS near-lossless (NEAR 2: lossy, bounded)",
              ["dcmcjpls", "+en", "+md", "2", "IN", "OUT"], tolerance=2 * slope)
    transcode(out, manifest, src, "ts-jpeg-2000-lossless", "JPEG 2000 Lossless", ["gdcmconv", "--j2k", "IN", "OUT"])
    # GE's private syntax (implicit VR little endian, pixels big endian) is outside the standard: refused.
    transcode(out, manifest, src, "ts-ge-private", "GE private Implicit VR Little Endian with big-endian pixels",
              ["dcmconv", "+tg", "IN", "OUT"], refusal="TransferSyntaxUID 1.2.840.113619.5.2")

    # 4D: time points, echoes, and b-values in each vendor's element.
    def temporal(d, v):
        d.TemporalPositionIdentifier = v + 1
        d.NumberOfTemporalPositions = 3
    four_d(out, manifest, "4d-temporal", "4D: three time points (TemporalPositionIdentifier)", flash, 3, temporal,
           "temporal position", 2)

    def echo(d, v):
        d.EchoNumbers = v + 1
        d.EchoTime = [2.46, 7.38][v]
    four_d(out, manifest, "4d-echoes", "4D: two echoes (EchoNumbers, EchoTime)", flash, 2, echo, "echo", 2)

    def b_standard(d, v):
        strip_private(d)
        d.add_new((0x0018, 0x9087), "FD", [0.0, 1000.0][v])
    def b_siemens(d, v):
        strip_private(d)
        private(d, 0x0019, "SIEMENS MR HEADER", 0x0C, "IS", [0, 1000][v])
    def b_ge(d, v):
        strip_private(d)
        d.Manufacturer = "GE MEDICAL SYSTEMS"
        private(d, 0x0043, "GEMS_PARM_01", 0x39, "IS", [[0, 8, 0, 0], [1000000000 + 1000, 8, 0, 0]][v])
    def b_philips(d, v):
        strip_private(d)
        d.Manufacturer = "Philips Medical Systems"
        private(d, 0x2001, "Philips Imaging DD 001", 0x03, "FL", [0.0, 1000.0][v])
    for vendor, tag in (("standard", b_standard), ("siemens", b_siemens), ("ge", b_ge), ("philips", b_philips)):
        four_d(out, manifest, f"4d-dwi-{vendor}", f"4D diffusion, b-values in the {vendor} element", flash, 2, tag,
               "b-value", 2)

    (out / "manifest.json").write_text(json.dumps(manifest, indent=1))


if __name__ == "__main__":
    main()
