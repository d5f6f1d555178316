// ImpulseWarmStart: a contact found again next frame starts from the force it carried, whatever
// the new order and tangents (or, with normal rows alone, its normal force); other contacts start
// from zero.
#include "contact/impulse_warm_start.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <vector>

#include "contact/contact_jacobian.h"

namespace hapsim::contact {
namespace {

Contact MakeContact(std::array<int, 3> nodes, const Eigen::Vector3d& n_W, int object = -1) {
  Contact contact;
  contact.SetBodyNodes({nodes[0], nodes[1], nodes[2]}, {1.0, 0.0, 0.0});
  contact.n_W = n_W.normalized();
  contact.rigid_object = object;
  return contact;
}

// The world force of contact i: λ_n n + λ_t1 t1 + λ_t2 t2 (CalcTangents of its normal).
Eigen::Vector3d WorldForce(const Contact& contact, const Eigen::VectorXd& lambda, int i) {
  Eigen::Vector3d t1, t2;
  CalcTangents(contact.n_W, &t1, &t2);
  return lambda[3 * i] * contact.n_W + lambda[3 * i + 1] * t1 + lambda[3 * i + 2] * t2;
}

TEST(ImpulseWarmStart, CarriesEachContactsForceToItsNewRowsAndTangents) {
  const std::vector<Contact> before = {MakeContact({4, -1, -1}, {0, 0, 1}),
                                       MakeContact({7, 8, 9}, {0.1, 0, 1}),
                                       MakeContact({2, -1, -1}, {0, 0, 1}, /*object=*/0)};
  Eigen::VectorXd lambda(9);
  lambda << 1.5, 0.2, -0.1, 0.7, 0.0, 0.3, 2.0, -0.4, 0.05;
  ImpulseWarmStart start;
  start.Record(before, lambda);

  // Next frame: another order, node 4's normal turned by 0.2 rad about x (the same
  // identity), node 2 now on the body rather than on the object, and a new contact at node 5.
  const Eigen::Vector3d turned = Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitX()) * before[0].n_W;
  const std::vector<Contact> after = {
      MakeContact({5, -1, -1}, {0, 0, 1}), MakeContact({7, 8, 9}, before[1].n_W),
      MakeContact({4, -1, -1}, turned), MakeContact({2, -1, -1}, {0, 0, 1})};
  const Eigen::VectorXd started = start.Start(after);
  ASSERT_EQ(started.size(), 12);
  EXPECT_EQ(start.num_carried(), 2);
  EXPECT_TRUE(started.segment<3>(0).isZero());  // new
  EXPECT_TRUE(started.segment<3>(9).isZero());  // another identity (no object)
  // Same normal: the same three numbers.
  EXPECT_LT((started.segment<3>(3) - lambda.segment<3>(3)).norm(), 1e-15);
  // Turned normal: the normal force kept, the tangential force projected onto the new plane.
  Eigen::Vector3d t1, t2;
  CalcTangents(before[0].n_W, &t1, &t2);
  const Eigen::Vector3d tangential_W = lambda[1] * t1 + lambda[2] * t2;
  const Eigen::Vector3d projected = tangential_W - turned.dot(tangential_W) * turned;
  EXPECT_DOUBLE_EQ(started[6], lambda[0]);
  EXPECT_LT((WorldForce(after[2], started, 2) - (lambda[0] * turned + projected)).norm(), 1e-14);
}

TEST(ImpulseWarmStart, ContactsWithoutBodyNodesOrFoundTwiceInEitherFrameStartAtZero) {
  const std::vector<Contact> before = {MakeContact({-1, -1, -1}, {0, 0, 1}, 1),  // tool on object
                                       MakeContact({3, -1, -1}, {0, 0, 1}),
                                       MakeContact({3, -1, -1}, {1, 0, 0})};  // node 3 twice
  ImpulseWarmStart start;
  start.Record(before, Eigen::VectorXd::Constant(9, 1.0));
  const Eigen::VectorXd started = start.Start(before);
  EXPECT_EQ(start.num_carried(), 0);
  EXPECT_TRUE(started.isZero());
  // Found once, then twice: neither of the two gets the one force.
  const std::vector<Contact> once = {MakeContact({6, -1, -1}, {0, 0, 1})};
  start.Record(once, Eigen::Vector3d(2.0, 0.1, 0.0));
  const std::vector<Contact> twice = {once[0], once[0]};
  EXPECT_TRUE(start.Start(twice).isZero());
  EXPECT_EQ(start.num_carried(), 0);
  EXPECT_LT((start.Start(once) - Eigen::Vector3d(2.0, 0.1, 0.0)).norm(), 1e-15);
  EXPECT_THROW(start.Record(before, Eigen::VectorXd::Zero(8)), std::invalid_argument);
}

// On an embedded collision surface two contacts whose points lie in one tet share their first
// nodes (the tet's); their surface points tell them apart, and each carries its own force.
TEST(ImpulseWarmStart, EmbeddedContactsInOneTetAreToldApartByTheirSurfacePoints) {
  std::vector<Contact> contacts = {MakeContact({10, 11, 12}, {0, 0, 1}),
                                   MakeContact({10, 11, 12}, {0, 0, 1})};
  contacts[0].embedded = contacts[1].embedded = true;
  contacts[0].surface_points = {3, -1, -1};
  contacts[1].surface_points = {4, -1, -1};
  Eigen::VectorXd lambda(6);
  lambda << 1.0, 0.1, 0.0, 2.0, -0.2, 0.0;
  ImpulseWarmStart start;
  start.Record(contacts, lambda);
  const std::vector<Contact> swapped = {contacts[1], contacts[0]};
  const Eigen::VectorXd started = start.Start(swapped);
  EXPECT_EQ(start.num_carried(), 2);
  EXPECT_LT((started.segment<3>(0) - lambda.segment<3>(3)).norm(), 1e-15);
  EXPECT_LT((started.segment<3>(3) - lambda.segment<3>(0)).norm(), 1e-15);
}

// Normal rows alone (the unilateral law): one number a contact, carried by identity as with three.
TEST(ImpulseWarmStart, NormalRowsAloneCarryTheNormalForce) {
  const std::vector<Contact> before = {MakeContact({4, -1, -1}, {0, 0, 1}),
                                       MakeContact({7, 8, 9}, {0.1, 0, 1}),
                                       MakeContact({5, -1, -1}, {0, 0, 1})};
  ImpulseWarmStart start(1);
  start.Record(before, Eigen::Vector3d(1.5, 0.0, 0.7));
  const std::vector<Contact> after = {before[2], MakeContact({6, -1, -1}, {0, 0, 1}), before[0],
                                      before[1]};
  const Eigen::VectorXd started = start.Start(after);
  ASSERT_EQ(started.size(), 4);
  EXPECT_EQ(start.num_carried(), 3);  // node 5's zero is carried too
  EXPECT_EQ(started, Eigen::Vector4d(0.7, 0.0, 1.5, 0.0));
  EXPECT_THROW(start.Record(before, Eigen::VectorXd::Zero(9)), std::invalid_argument);
  EXPECT_THROW(ImpulseWarmStart(2), std::invalid_argument);
}

}  // namespace
}  // namespace hapsim::contact
