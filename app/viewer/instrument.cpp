#include "viewer/instrument.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace tpb::app {

std::vector<AxisTick> niceTicks(double lo, double hi, int maxTicks) {
    std::vector<AxisTick> ticks;
    if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi)) return ticks;
    maxTicks = std::max(maxTicks, 2);
    // The smallest round step that gives at most maxTicks ticks.
    const double raw = (hi - lo) / maxTicks;
    const double decade = std::pow(10.0, std::floor(std::log10(raw)));
    double step = 10.0 * decade;
    for (double m : {1.0, 2.0, 5.0, 10.0})
        if (m * decade >= raw) {
            step = m * decade;
            break;
        }
    const int decimals = std::max(0, -static_cast<int>(std::floor(std::log10(step) + 1e-9)));
    for (double k = std::ceil(lo / step - 1e-9); k * step <= hi + 1e-9 * step; k += 1.0) {
        char label[32];
        const double v = k * step;
        std::snprintf(label, sizeof label, "%.*f", decimals, v == 0.0 ? 0.0 : v);
        ticks.push_back({v, label});
    }
    return ticks;
}

std::vector<float> logScale(const std::vector<float>& values, float decades) {
    std::vector<float> out(values.size(), 0.0f);
    float peak = 0.0f;
    for (float v : values)
        if (std::isfinite(v)) peak = std::max(peak, v);
    if (!(peak > 0.0f) || !(decades > 0.0f)) return out;
    for (size_t i = 0; i < values.size(); ++i) {
        const float v = values[i];
        if (!(v > 0.0f) || !std::isfinite(v)) continue;
        out[i] = std::clamp(1.0f + std::log10(v / peak) / decades, 0.0f, 1.0f);
    }
    return out;
}

void BatchNoise::reset(size_t pixels) {
    prevSum_.assign(pixels, 0.0);
    sumW_x_.assign(pixels, 0.0);
    sumW_x2_.assign(pixels, 0.0);
    prevWeight_ = sumW_ = 0.0;
    batches_ = 0;
}

void BatchNoise::add(const std::vector<float>& mean, double weight) {
    const double w = weight - prevWeight_;
    if (!(w > 0.0) || mean.size() != prevSum_.size()) return;
    for (size_t i = 0; i < mean.size(); ++i) {
        const double sum = weight * static_cast<double>(mean[i]);
        const double x = (sum - prevSum_[i]) / w;  // the batch's own mean
        sumW_x_[i] += w * x;
        sumW_x2_[i] += w * x * x;
        prevSum_[i] = sum;
    }
    prevWeight_ = weight;
    sumW_ += w;
    ++batches_;
}

double BatchNoise::relativeError() const {
    if (batches_ < 2 || !(sumW_ > 0.0)) return -1.0;
    // Per pixel: a batch of weight w has the variance s^2 / w of one unit-weight pass's s^2, so
    // E[sum w (x - mean)^2] = (B - 1) s^2 over B batches, and the film's mean has s^2 / W.
    const double dof = static_cast<double>(batches_ - 1);
    double se2 = 0.0, level = 0.0;
    for (size_t i = 0; i < sumW_x_.size(); ++i) {
        const double m = sumW_x_[i] / sumW_;
        const double var = std::max(0.0, (sumW_x2_[i] - sumW_ * m * m) / dof);
        se2 += var / sumW_;
        level += m;
    }
    const double n = static_cast<double>(sumW_x_.size());
    if (!(level > 0.0)) return -1.0;
    return std::sqrt(se2 / n) / (level / n);
}

}  // namespace tpb::app
