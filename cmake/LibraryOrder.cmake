# SPDX-License-Identifier: Apache-2.0
# The libraries (top-level folders) in dependency order: each may include the
# headers of those before it, never of one after it. This is the one place the
# order is written: the top CMakeLists.txt includes it, tests/layout/Layering.cmake
# checks every #include against it and checks that the chain shown in the
# README's "Layout" and docs/architecture.md is this one.
set(VOXHAP_LIBRARY_ORDER
    core volume phantoms registration segmentation fusion haptic assessment planning batch render regress bench tools python)
