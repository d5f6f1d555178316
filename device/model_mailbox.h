#pragma once
// Hands the newest contact model from the receive thread to the 1 kHz haptic loop without a lock
// (issue 4: "a receive thread double-buffers the newest model; the loop takes no lock beyond a
// swap"). A triple buffer: the writer fills its private slot and swaps it with the shared middle
// slot; the loop, when the middle slot holds something new, swaps its own slot with it. Each side
// touches only its own slot between swaps, so neither waits, and a model is never torn. Models
// that arrive faster than the loop takes them are overwritten (only the newest matters).
//
// One writer thread and one reader thread; the swaps are single atomic exchanges. The same
// buffer carries the external driver's device states (apps/haptic_command.cc).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

#include "contact/haptic_lcp_solver.h"
#include "contact/linear_contact_model.h"
#include "core/rigid_tool.h"

namespace hapsim::device {

// One visual frame's output as the haptic loop uses it.
struct ContactModelUpdate {
  std::int64_t sequence = -1;         // visual frame index (contact_model_t.sequence)
  std::int64_t published_utime = 0;   // when the visual process published it, µs (latency)
  std::int64_t ready_utime = 0;       // when the receiver had it decoded and prepared, µs
  contact::LinearContactModel model;  // the paper's model
  contact::ContactRows rows;          // lcp mode: the frame's rows (num_rows 0 otherwise)
  ToolState visual_tool;              // coupling mode: the visual tool after the frame
  ToolState linearised_tool;          // the haptic tool the model was linearised at (pose)
  // lcp mode: a solver prepared for `rows` by the receive thread (PrepareLcpUpdate), used by the
  // loop while this update is the newest; null otherwise.
  std::unique_ptr<contact::HapticLcpSolver> lcp_solver;
  // The frame's world, for the geometric modes and godobject (contact_model_t.body_x_W_m ...):
  // the body's node positions (3N, world, m) and the rigid objects' poses; has_world false when
  // the model carried none.
  bool has_world = false;
  Eigen::VectorXd body_x_m;
  std::vector<Eigen::Isometry3d> object_poses;
};

// The newest value from one writer thread to one reader thread.
template <typename T>
class TripleBuffer {
 public:
  // Writer: the slot to fill (private to the writer until Publish).
  T* writer_slot() { return &slots_[writer_]; }
  // Writer: makes the filled slot the newest; the writer gets another slot to fill next.
  void Publish() {
    // acq_rel: the slot's contents happen-before the reader's acquire of the same exchange chain.
    const std::uint8_t old = middle_.exchange(writer_ | kFresh, std::memory_order_acq_rel);
    writer_ = old & 3;
  }
  // Setup only, before the writer and the reader run: every slot, to give each in advance what it
  // will hold (so that neither thread allocates it later).
  std::array<T, 3>& slots_for_setup() { return slots_; }
  // Reader: the newest value if one was published since the last call, else nullptr. The slot
  // stays the reader's (unchanged) until its next call that returns non-null.
  const T* TakeNewest() {
    if (!(middle_.load(std::memory_order_acquire) & kFresh)) return nullptr;
    const std::uint8_t old = middle_.exchange(reader_, std::memory_order_acq_rel);
    reader_ = old & 3;
    return &slots_[reader_];
  }

 private:
  static constexpr std::uint8_t kFresh = 4;  // bit set in middle_ while it holds an unread value
  std::array<T, 3> slots_;
  std::atomic<std::uint8_t> middle_{1};
  std::uint8_t writer_ = 0;  // touched by the writer only
  std::uint8_t reader_ = 2;  // touched by the reader only
};

using ModelMailbox = TripleBuffer<ContactModelUpdate>;

}  // namespace hapsim::device
