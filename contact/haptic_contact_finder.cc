#include "contact/haptic_contact_finder.h"

#include <algorithm>
#include <stdexcept>

namespace hapsim::contact {
namespace {

DetectionOptions MakeDetectionOptions(double margin_m) {
  DetectionOptions options;
  options.margin_m = margin_m;
  options.continuous = false;  // the tool's pose alone; the caller's margin is its prediction
  // Node contacts only (the header says why).
  options.edge_contacts = false;
  options.feature_contacts = false;
  return options;
}

}  // namespace

HapticContactFinder::HapticContactFinder(const fem::Model* body, const ToolShape& tool,
                                         const std::vector<RigidObject>& objects,
                                         double max_margin_m)
    : max_margin_m_(max_margin_m), objects_(objects, tool, max_margin_m) {
  if (!(max_margin_m >= 0.0)) throw std::invalid_argument("HapticContactFinder: margin < 0");
  if (body != nullptr) {
    detector_ =
        std::make_unique<CollisionDetector>(*body, tool, MakeDetectionOptions(max_margin_m));
    x_body_m_ = body->rest_positions_m;
    SetBodyPositions(x_body_m_);
  }
}

HapticContactFinder::~HapticContactFinder() = default;

void HapticContactFinder::SetBodyPositions(const Eigen::VectorXd& x_m) {
  if (!detector_) return;
  if (x_m.size() != x_body_m_.size()) {
    throw std::invalid_argument("HapticContactFinder::SetBodyPositions: wrong size");
  }
  x_body_m_ = x_m;
  detector_->Refit(x_body_m_);  // once a frame; Find searches these positions without refitting
}

void HapticContactFinder::Find(const Eigen::Isometry3d& X_WT, double margin_m,
                               std::vector<Contact>* contacts) {
  contacts->clear();
  // In [0, max_margin_m] whatever is asked (NaN too: SetMargin must not throw in the loop).
  margin_m = margin_m >= 0.0 ? std::min(margin_m, max_margin_m_) : 0.0;
  if (detector_) detector_->SetMargin(margin_m);
  if (detector_)
    detector_->Detect(x_body_m_, X_WT, x_body_m_, X_WT, contacts, /*refit_tree=*/false);
  objects_.AddToolContacts(X_WT, X_WT, contacts);
  // Both detectors report up to max_margin_m; keep those within the margin asked for.
  const double threshold_m = margin_m;
  contacts->erase(std::remove_if(contacts->begin(), contacts->end(),
                                 [threshold_m](const Contact& c) { return c.gap_m > threshold_m; }),
                  contacts->end());
}

}  // namespace hapsim::contact
