#pragma once
// A one-line progress bar on stderr for long runs, drawn only when stderr is a terminal (logs and
// CI output stay clean). Redraws at most every 100 ms.

#include <chrono>
#include <string>

namespace hapsim {

class ProgressBar {
 public:
  ProgressBar(std::string label, long total);
  ~ProgressBar();  // finishes the line if it was drawn
  void Update(long done);

 private:
  void Draw(long done);
  std::string label_;
  long total_;
  bool enabled_;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace hapsim
