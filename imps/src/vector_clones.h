// SPDX-License-Identifier: MIT
// IMPS_VECTOR_CLONES: a loop compiled twice, for AVX2 and for the baseline, and chosen at run time. Both give the
// same bits: IEEE add, multiply, divide, min and max are exact per lane, and -ffp-contract=off rules out fused
// multiply-adds. (clang 16 cannot clone templates; its builds, the fuzz targets, use the baseline only.) Internal.
#pragma once

#if defined(__clang__)
#define IMPS_VECTOR_CLONES
#else
#define IMPS_VECTOR_CLONES __attribute__((target_clones("avx2", "default")))
#endif
