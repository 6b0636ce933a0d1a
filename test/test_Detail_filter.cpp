#include "test_support.h"

#include <CGAL_ext/Detail_filter.h>

#include <gtest/gtest.h>

using namespace CGAL_ext;

TEST(DetailFilter, ResponseVanishesAtZeroForEveryOrder)
{
  for(Detail_order o : all_orders) EXPECT_EQ(Detail_filter({o, 0.3, 1.8}).response(0.0), 0.0);
}

TEST(DetailFilter, QuadricResponseIsOneAtLambdaAndMu)
{
  const Detail_filter f{Detail_order::quadric, 0.8, 1.6};
  EXPECT_NEAR(f.response(0.8), 1.0, 1e-14);
  EXPECT_NEAR(f.response(1.6), 1.0, 1e-14);
  EXPECT_GT(f.response(1.2), 1.0); // the pass band is amplified
}

TEST(DetailFilter, LinearResponseIsKOverLambda)
{
  const Detail_filter f{Detail_order::linear, 0.3, 0};
  for(double k : {0.1, 0.5, 1.7}) EXPECT_NEAR(f.response(k), k / 0.3, 1e-14);
}

TEST(DetailFilter, CubicResponseMatchesThePapersPolynomial)
{
  const double l = 0.3, m = 1.8;
  const Detail_filter f{Detail_order::cubic, l, m};
  for(double k : {0.05, 0.3, 0.9, 1.8, 2.0}) {
    const double paper = (1 / (l * l) + 1 / (l * m) + 1 / (m * m)) * k * k - (1 / (l * m)) * (1 / l + 1 / m) * k * k * k;
    EXPECT_NEAR(f.response(k), paper, 1e-12 * std::abs(paper) + 1e-14);
  }
  // Like the quadric, it passes through 1 at lambda and mu.
  EXPECT_NEAR(f.response(l), 1.0, 1e-12);
  EXPECT_NEAR(f.response(m), 1.0, 1e-12);
}

TEST(DetailFilter, DegreeFollowsTheOrder)
{
  EXPECT_EQ(Detail_filter({Detail_order::linear}).degree(), 1);
  EXPECT_EQ(Detail_filter({Detail_order::quadric}).degree(), 2);
  EXPECT_EQ(Detail_filter({Detail_order::cubic}).degree(), 3);
}

TEST(DetailFilter, DefaultsAreThePapersQuadric)
{
  const Detail_filter f;
  EXPECT_EQ(f.order, Detail_order::quadric);
  EXPECT_EQ(f.lambda, 0.8);
  EXPECT_EQ(f.mu, 1.6);
  EXPECT_NO_THROW(f.validate());
}

TEST(DetailFilter, InvalidLambdaOrMuIsRejectedWithAMessage)
{
  EXPECT_THROW(Detail_filter({Detail_order::linear, 0.0, 0}).validate(), Invalid_input);
  EXPECT_THROW(Detail_filter({Detail_order::linear, -1.0, 0}).validate(), Invalid_input);
  EXPECT_THROW(Detail_filter({Detail_order::quadric, 0.8, 0.8}).validate(), Invalid_input);
  EXPECT_THROW(Detail_filter({Detail_order::cubic, 0.8, 0.5}).validate(), Invalid_input);
  EXPECT_THROW(Detail_filter({Detail_order::quadric, std::nan(""), 1.6}).validate(), Invalid_input);
  // mu is not used by the linear order, so it is not checked there.
  EXPECT_NO_THROW(Detail_filter({Detail_order::linear, 0.8, 0.1}).validate());
  try {
    Detail_filter({Detail_order::quadric, 0.8, 0.5}).validate();
    FAIL();
  } catch(const Invalid_input& e) {
    EXPECT_NE(std::string(e.what()).find("mu"), std::string::npos) << e.what();
  }
  EXPECT_THROW((Laplacian_weights{Laplacian_weighting::distance_power, INFINITY}.validate()), Invalid_input);
}
