// Small helpers the synth sources share (one definition, so that the sources
// can also be compiled together in a unity build).
#pragma once

#include <random>

namespace docunfold::synth {

inline constexpr double kPi = 3.14159265358979323846;

// A uniform draw in [lo, hi).
inline double Uniform(std::mt19937* rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(*rng);
}

}  // namespace docunfold::synth
