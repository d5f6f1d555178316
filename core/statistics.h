#pragma once
// Summary statistics of measured samples (timings, iteration counts).

#include <algorithm>
#include <numeric>
#include <vector>

namespace hapsim {

// Median (mean of the two middle values for an even count); 0 for no samples.
inline double Median(std::vector<double> samples) {
  if (samples.empty()) return 0.0;
  const size_t middle = samples.size() / 2;
  std::nth_element(samples.begin(), samples.begin() + middle, samples.end());
  const double upper = samples[middle];
  if (samples.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(samples.begin(), samples.begin() + middle));
}

// The sample at quantile q in [0, 1] (nearest rank: q = 1 is the maximum); 0 for no samples.
inline double Quantile(std::vector<double> samples, double q) {
  if (samples.empty()) return 0.0;
  const size_t k = std::min(samples.size() - 1,
                            static_cast<size_t>(q * static_cast<double>(samples.size() - 1) + 0.5));
  std::nth_element(samples.begin(), samples.begin() + static_cast<long>(k), samples.end());
  return samples[k];
}

inline double Mean(const std::vector<double>& samples) {
  if (samples.empty()) return 0.0;
  return std::accumulate(samples.begin(), samples.end(), 0.0) / static_cast<double>(samples.size());
}

}  // namespace hapsim
