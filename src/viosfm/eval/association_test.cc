#include "viosfm/eval/association.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "viosfm/util/errors.h"

namespace viosfm {
namespace {

using ::testing::ElementsAre;

// Seconds that are exact binary fractions, so that evo's double arithmetic
// sees the same ties as exact ns arithmetic.
timestamp_ns_t S(double seconds) {
  return static_cast<timestamp_ns_t>(seconds * 1e9);
}

std::vector<timestamp_ns_t> Stamps(std::initializer_list<double> seconds) {
  std::vector<timestamp_ns_t> stamps;
  for (double s : seconds) stamps.push_back(S(s));
  return stamps;
}

PosePair P(size_t est, size_t ref) {
  return {est, ref};
}

TEST(AssociateByIndex, TakesTheFirstMinCountPairs) {
  EXPECT_THAT(AssociateByIndex(3, 5), ElementsAre(P(0, 0), P(1, 1), P(2, 2)));
  EXPECT_THAT(AssociateByIndex(2, 2), ElementsAre(P(0, 0), P(1, 1)));
  EXPECT_TRUE(AssociateByIndex(0, 4).empty());
}

TEST(AssociateNearest, ShorterEstimateTakesNearestReferenceEarlierWinsTies) {
  const auto est = Stamps({1.0, 2.0, 3.0});
  const auto ref = Stamps({0.75, 1.5, 1.75, 2.25, 4.0});
  // 1.0 -> 0.75 (0.25 s); 2.0 -> 1.75 and 2.25 tie, the earlier wins;
  // 3.0 -> nearest 2.25 is 0.75 s away, beyond 0.5 s.
  EXPECT_THAT(AssociateNearest(est, ref, S(0.5)), ElementsAre(P(0, 0), P(1, 2)));
}

TEST(AssociateNearest, ShorterReferenceIsIteratedAndEstimatePosesRepeat) {
  const auto est = Stamps({1.0, 2.0, 3.0, 4.0});
  const auto ref = Stamps({1.75, 2.25, 3.5});
  // ref 1.75 and 2.25 both take est 2.0; ref 3.5 ties 3.0 / 4.0 at exactly
  // max_dt (accepted: |dt| <= max_dt), the earlier wins.
  EXPECT_THAT(AssociateNearest(est, ref, S(0.5)), ElementsAre(P(1, 0), P(1, 1), P(2, 2)));
  EXPECT_THAT(AssociateNearest(est, ref, S(0.25)), ElementsAre(P(1, 0), P(1, 1)));
}

TEST(AssociateNearest, EqualLengthsIterateTheEstimate) {
  const auto est = Stamps({1.0, 1.25});
  const auto ref = Stamps({1.125, 2.0});
  // est 1.0 -> ref 1.125; est 1.25 -> ref 1.125 (0.125) rather than 2.0.
  EXPECT_THAT(AssociateNearest(est, ref, S(0.5)), ElementsAre(P(0, 0), P(1, 0)));
  // Iterating the reference instead would pair ref 2.0 with nothing and ref
  // 1.125 with est 1.0 (the earlier of a tie): a different answer.
}

TEST(AssociateNearest, RepeatedStampFirstWins) {
  const auto est = Stamps({1.0});
  const auto ref = Stamps({0.5, 0.75, 0.75, 2.0});
  EXPECT_THAT(AssociateNearest(est, ref, S(0.5)), ElementsAre(P(0, 1)));
}

TEST(AssociateNearest, OffsetIsAddedToTheEstimate) {
  const auto est = Stamps({0.0, 1.0, 2.0});
  const auto ref = Stamps({10.0, 11.0, 12.0, 13.0});
  EXPECT_TRUE(AssociateNearest(est, ref, S(0.01)).empty());
  EXPECT_THAT(AssociateNearest(est, ref, S(0.01), S(10.0)), ElementsAre(P(0, 0), P(1, 1), P(2, 2)));
  // Same with the reference iterated (the reference is the shorter one).
  EXPECT_THAT(AssociateNearest(Stamps({0.0, 1.0, 2.0, 3.0, 4.0}), ref, S(0.01), S(10.0)),
              ElementsAre(P(0, 0), P(1, 1), P(2, 2), P(3, 3)));
}

TEST(AssociateNearest, ExactTieIsDecidedAsEvoDoesInDoubleSeconds) {
  // From the TUM fr2/desk files: 1311868226.310950 is exactly 1.65 ms from
  // both 1311868226.3093 and 1311868226.3126. As Python floats the later one
  // is nearer, and evo takes it.
  const std::vector<timestamp_ns_t> est = {1311868226310950000};
  const std::vector<timestamp_ns_t> ref = {1311868226309300000, 1311868226312600000};
  EXPECT_THAT(AssociateNearest(est, ref, 10'000'000), ElementsAre(P(0, 1)));
}

TEST(AssociateNearest, EmptyInputsGiveNoPairs) {
  EXPECT_TRUE(AssociateNearest({}, Stamps({1.0}), S(1.0)).empty());
  EXPECT_TRUE(AssociateNearest(Stamps({1.0}), {}, S(1.0)).empty());
}

TEST(AssociateNearest, UnsortedStampsAreAnInternalError) {
  EXPECT_THROW(AssociateNearest(Stamps({2.0, 1.0}), Stamps({1.0}), S(1.0)), InternalError);
}

TEST(AssociateGreedy, EachStampUsedOnceSmallestDifferenceFirst) {
  const auto est = Stamps({1.0, 1.25});
  const auto ref = Stamps({1.125, 1.5});
  // Candidates: (e1, r0) 0.125, (e0, r0) 0.125, (e1, r1) 0.25 (e0, r1 is
  // 0.5, not < 0.5). Ties sort by reference then estimate stamp: (e0, r0)
  // wins, then (e1, r0) is blocked, then (e1, r1).
  EXPECT_THAT(AssociateGreedy(est, ref, S(0.5)), ElementsAre(P(0, 0), P(1, 1)));
  // The nearest rule lets both estimates take ref 1.125.
  EXPECT_THAT(AssociateNearest(est, ref, S(0.5)), ElementsAre(P(0, 0), P(1, 0)));
}

TEST(AssociateGreedy, PrefersTheClosestPairOverTheFirst) {
  const auto est = Stamps({1.0, 1.25});
  const auto ref = Stamps({1.1875, 1.75});
  // (e1, r0) 0.0625 is taken first; e0's only candidate r0 is then used.
  EXPECT_THAT(AssociateGreedy(est, ref, S(0.25)), ElementsAre(P(1, 0)));
}

TEST(AssociateGreedy, ToleranceIsStrictAndOffsetApplies) {
  EXPECT_TRUE(AssociateGreedy(Stamps({1.0}), Stamps({1.25}), S(0.25)).empty());
  EXPECT_THAT(AssociateGreedy(Stamps({1.0}), Stamps({1.25}), S(0.25), S(0.125)),
              ElementsAre(P(0, 0)));
}

TEST(AssociationMethod, ParsesNames) {
  EXPECT_EQ(ParseAssociationMethod("Nearest"), AssociationMethod::kNearest);
  EXPECT_EQ(ParseAssociationMethod("greedy"), AssociationMethod::kGreedy);
  EXPECT_EQ(ParseAssociationMethod("index"), AssociationMethod::kIndex);
  EXPECT_EQ(AssociationMethodName(AssociationMethod::kAuto), "auto");
  EXPECT_THROW(ParseAssociationMethod("closest"), InputError);
}

}  // namespace
}  // namespace viosfm
