// The viewer's measuring aids, without GL or ImGui (tested on their own: tests/viewer/
// test_instrument.cpp): tick marks for the time axes of the streak and the profile, the log scale
// of the profile, and the noise estimate of the picture from the spread between passes.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace tpb::app {

// A tick of an axis: its value and its label ("12.5").
struct AxisTick {
    double value = 0.0;
    std::string label;
};

// Ticks at a round step (1, 2 or 5 x 10^k) inside [lo, hi], at most `maxTicks` of them (>= 2),
// labelled with as many decimals as the step needs. None when the range is empty or not finite.
std::vector<AxisTick> niceTicks(double lo, double hi, int maxTicks);

// The profile on a log scale: log10(v / peak) clamped to [-decades, 0], as the height above the
// floor in [0, 1] (0: at most peak x 10^-decades or no light, 1: the peak). All 0 without light.
std::vector<float> logScale(const std::vector<float>& values, float decades);

// How far the picture is from converged (its variance part; the kernels' bias is not seen): the
// film is a weighted average of batches (one or more passes each, as the UI thread saw them
// complete), so each pixel's batch means scatter around it; the weighted variance of that scatter
// over the batches, divided by the total weight, is the variance of the film's value (batch means).
// The estimate: the relative standard error of the image, sqrt(mean over pixels of SE^2) over the
// mean pixel value (luminance), from at least 2 batches.
class BatchNoise {
public:
    // Starts over for an image of `pixels` values (luminance per pixel).
    void reset(size_t pixels);
    // The film now: its average `mean` (per pixel) with total weight `weight` (the sum of its passes'
    // weights); the batch since the last add is recovered as (W_n m_n - W_{n-1} m_{n-1}) / w.
    // An add with no new weight is ignored.
    void add(const std::vector<float>& mean, double weight);
    int batches() const { return batches_; }
    // The relative standard error (0.03: 3 %); negative when not known yet (< 2 batches, no light).
    double relativeError() const;

private:
    std::vector<double> prevSum_;           // W_{n-1} m_{n-1} per pixel
    std::vector<double> sumW_x_, sumW_x2_;  // sum over batches of w x and w x^2 per pixel
    double prevWeight_ = 0.0, sumW_ = 0.0;
    int batches_ = 0;
};

}  // namespace tpb::app
