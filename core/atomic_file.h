#pragma once
// All-or-nothing output files: a reader never sees a half-written result.

#include <functional>
#include <ostream>
#include <string>

namespace hapsim {

// Significant digits that make every double round-trip exactly through text.
constexpr int kRoundTripDigits = 17;

// `write` fills path + ".tmp" (stream set to kRoundTripDigits precision), which is renamed over
// `path` once complete. Throws InputError (line 0) if the file cannot be opened, written or
// renamed; the temporary file is removed then. An exception from `write` also removes it.
void WriteFileAtomically(const std::string& path, const std::function<void(std::ostream&)>& write);

// Creates `dir` and its parents if missing (nothing for ""). Throws InputError naming the folder
// and the command-line `key` it came from when it cannot.
void CreateOutputDirectory(const std::string& dir, const std::string& key = "--out");

}  // namespace hapsim
