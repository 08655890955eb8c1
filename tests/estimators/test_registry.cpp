// The estimator registry (estimators/registry.cpp) and the list of names the settings check reads
// (estimators/estimator_names.h) agree: every listed name makes an estimator that answers to it,
// and an unknown name makes none.
#include "estimators/estimator.h"

#include <gtest/gtest.h>

#include <set>

using namespace tpb;

TEST(EstimatorRegistry, EveryListedNameMakesItsEstimator) {
    ASSERT_FALSE(volumeEstimatorNames().empty());
    EXPECT_EQ(volumeEstimatorNames().front(), "beam2d");  // the default comes first
    std::set<std::string> seen;
    for (const std::string& n : volumeEstimatorNames()) {
        EXPECT_TRUE(seen.insert(n).second) << n << " listed twice";
        const auto e = makeVolumeEstimator(n);
        ASSERT_NE(e, nullptr) << n;
        EXPECT_EQ(e->name(), n);
        EXPECT_GE(e->dim(), 1);
        EXPECT_LE(e->dim(), 3);
        EXPECT_TRUE(e->needs().beams || e->needs().points) << n << " needs nothing from the photon pass";
        EXPECT_TRUE(e->empty()) << n << ": nothing to gather before prepare()";
    }
    for (const std::string& n : surfaceEstimatorNames()) {
        const auto e = makeSurfaceEstimator(n);
        ASSERT_NE(e, nullptr) << n;
        EXPECT_EQ(e->name(), n);
        EXPECT_EQ(e->dim(), 2);
    }
    EXPECT_EQ(makeVolumeEstimator("beam3d"), nullptr);
    EXPECT_EQ(makeSurfaceEstimator(""), nullptr);
}
