// Dot products of SIFT descriptors with AVX2 integer instructions, for the
// exact matcher (matching.cc). Kept to plain pointers and intrinsics: this
// is the one file compiled with -mavx2, and any inline template it shared
// with the rest of the program (std::vector, Eigen) could be linked in its
// AVX2 form and run on a CPU without it.
#pragma once

#include <cstddef>
#include <cstdint>

namespace docunfold::sfm {

// b_packed's layout: b's rows in blocks of 8 (the last one padded with zero
// rows); in each block, for each pair of dimensions p = 0..63, the 8 rows'
// (b[2p], b[2p+1]) one row after the other: 1024 int16 a block.
constexpr int kDotBlockRows = 8;
constexpr int kDotBlockValues = kDotBlockRows * 128;

// Whether this build has DescriptorDotsAvx2 and this CPU can run it.
bool HaveDescriptorDotsAvx2();

// dots[i * stride + j] = a_i . b_j for i < na and j < 8 * blocks (the padded
// columns get 0): a holds na rows of 128 values in 0..255, b_packed `blocks`
// blocks as above; stride >= 8 * blocks. Integer sums: exact.
void DescriptorDotsAvx2(const int16_t* a, int na, const int16_t* b_packed, int blocks,
                        int32_t* dots, size_t stride);

}  // namespace docunfold::sfm
