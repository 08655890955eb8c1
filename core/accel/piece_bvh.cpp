#include "accel/piece_bvh.h"

#include <algorithm>
#include <cmath>

namespace tpb {

namespace {

// 11 bits of x spread to every third bit (bits 0, 3, ..., 30).
uint64_t spread3(uint64_t x) {
    x &= 0x7ffu;
    x = (x | (x << 16)) & 0x00000000ff0000ffull;
    x = (x | (x << 8)) & 0x000000f00f00f00full;
    x = (x | (x << 4)) & 0x00000c30c30c30c3ull;
    x = (x | (x << 2)) & 0x0000249249249249ull;
    return x;
}

// The interior of a node is bounded by at most 128 entries of the traversal's stack: the depth is
// capped well below that (a range that deep becomes one leaf, however many boxes it holds).
constexpr int kMaxDepth = 100;

}  // namespace

void PieceBvh::build(const std::vector<Box>& boxes) {
    nodes_.clear();
    const size_t n = boxes.size();
    order_.resize(n);
    if (n == 0) return;
    // Morton codes of the centres over their bounds (a flat axis maps to 0).
    float lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (const Box& b : boxes)
        for (int a = 0; a < 3; ++a) {
            const float c = 0.5f * (b.lo[a] + b.hi[a]);
            lo[a] = std::min(lo[a], c);
            hi[a] = std::max(hi[a], c);
        }
    double scale[3];
    for (int a = 0; a < 3; ++a) scale[a] = hi[a] > lo[a] ? 2047.0 / (static_cast<double>(hi[a]) - lo[a]) : 0.0;
    codes_.resize(n);
    for (size_t i = 0; i < n; ++i) {
        uint64_t code = 0;
        for (int a = 0; a < 3; ++a) {
            const double c = 0.5 * (static_cast<double>(boxes[i].lo[a]) + boxes[i].hi[a]);
            const double q = std::clamp((c - lo[a]) * scale[a], 0.0, 2047.0);  // NaN -> 0 below
            code |= spread3(static_cast<uint64_t>(q >= 0.0 ? q : 0.0)) << a;
        }
        codes_[i] = code;
        order_[i] = static_cast<uint32_t>(i);
    }
    // LSD radix sort of (code, index), 11 bits per pass: stable, so equal codes keep index order.
    scratchCodes_.resize(n);
    scratchOrder_.resize(n);
    for (int shift = 0; shift < 33; shift += 11) {
        uint32_t count[2049] = {};
        for (size_t i = 0; i < n; ++i) ++count[((codes_[i] >> shift) & 0x7ffu) + 1];
        for (int b = 0; b < 2048; ++b) count[b + 1] += count[b];
        for (size_t i = 0; i < n; ++i) {
            const uint32_t slot = count[(codes_[i] >> shift) & 0x7ffu]++;
            scratchCodes_[slot] = codes_[i];
            scratchOrder_[slot] = order_[i];
        }
        codes_.swap(scratchCodes_);
        order_.swap(scratchOrder_);
    }
    sorted_.resize(n);
    for (size_t i = 0; i < n; ++i) sorted_[i] = boxes[order_[i]];
    nodes_.reserve(2 * (n / kLeafSize + 1));
    buildRange(0, static_cast<uint32_t>(n), 0);
    nodes4_.clear();
    nodes4_.reserve(nodes_.size() / 2 + 1);
    collapse(0);
}

// Node4 for the binary subtree at `binary`: its children, opened (the largest first) until there
// are four or only leaves. Its boxes are padded by 1e-6 of their coordinates (+1e-6) so that the
// float slab test never rejects a box that the double test of the leaf's boxes would accept.
uint32_t PieceBvh::collapse(uint32_t binary) {
    uint32_t slot[4];
    int slots = 0;
    if (nodes_[binary].count > 0) {
        slot[slots++] = binary;  // a root that is a leaf
    } else {
        slot[slots++] = binary + 1;
        slot[slots++] = nodes_[binary].first;
        while (slots < 4) {
            int open = -1;
            float best = -1.0f;
            for (int j = 0; j < slots; ++j) {
                const Node& c = nodes_[slot[j]];
                if (c.count > 0) continue;
                const float dx = c.hi[0] - c.lo[0], dy = c.hi[1] - c.lo[1], dz = c.hi[2] - c.lo[2];
                const float area = dx * dy + dy * dz + dz * dx;
                if (area > best) {
                    best = area;
                    open = j;
                }
            }
            if (open < 0) break;
            const uint32_t b = slot[open];
            slot[open] = b + 1;
            slot[slots++] = nodes_[b].first;
        }
    }
    const uint32_t index = static_cast<uint32_t>(nodes4_.size());
    nodes4_.push_back({});
    uint32_t child[4] = {0, 0, 0, 0}, count[4] = {0, 0, 0, 0};
    for (int j = 0; j < slots; ++j) {
        const Node& c = nodes_[slot[j]];
        if (c.count > 0) {
            child[j] = c.first;
            count[j] = c.count;
        } else {
            child[j] = collapse(slot[j]);
        }
    }
    Node4& node = nodes4_[index];
    node.slots = slots;
    for (int j = 0; j < 4; ++j) {
        node.child[j] = child[j];
        node.count[j] = count[j];
        for (int a = 0; a < 3; ++a) {
            if (j >= slots) {  // unused: a box no segment meets (lo > hi on every axis)
                node.lo[a][j] = 1.0f;
                node.hi[a][j] = -1.0f;
                continue;
            }
            const Node& c = nodes_[slot[j]];
            node.lo[a][j] = c.lo[a] - 1e-6f * (1.0f + std::abs(c.lo[a]));
            node.hi[a][j] = c.hi[a] + 1e-6f * (1.0f + std::abs(c.hi[a]));
        }
    }
    return index;
}

// Builds the subtree over order_[begin, end) and returns its root's index.
uint32_t PieceBvh::buildRange(uint32_t begin, uint32_t end, int depth) {
    const uint32_t index = static_cast<uint32_t>(nodes_.size());
    nodes_.push_back({});
    if (end - begin <= static_cast<uint32_t>(kLeafSize) || depth >= kMaxDepth) {
        Node leaf;
        for (int a = 0; a < 3; ++a) {
            leaf.lo[a] = INFINITY;
            leaf.hi[a] = -INFINITY;
        }
        for (uint32_t k = begin; k < end; ++k) {
            const Box& b = sorted_[k];
            for (int a = 0; a < 3; ++a) {
                leaf.lo[a] = std::min(leaf.lo[a], b.lo[a]);
                leaf.hi[a] = std::max(leaf.hi[a], b.hi[a]);
            }
        }
        leaf.first = begin;
        leaf.count = end - begin;
        nodes_[index] = leaf;
        return index;
    }
    // Split where the highest differing bit of the range's codes turns on (sorted: one place).
    uint32_t split = begin + (end - begin) / 2;
    const uint64_t first = codes_[begin], last = codes_[end - 1];
    if (first != last) {
        const int bit = 63 - __builtin_clzll(first ^ last);
        const uint64_t mask = ~uint64_t(0) << bit;  // codes at or above the split share the prefix + bit
        const uint64_t target = (last & mask);
        split = static_cast<uint32_t>(std::lower_bound(codes_.begin() + begin, codes_.begin() + end, target,
                                                       [mask](uint64_t c, uint64_t t) { return (c & mask) < t; }) -
                                      codes_.begin());
    }
    buildRange(begin, split, depth + 1);
    const uint32_t right = buildRange(split, end, depth + 1);
    const Node &l = nodes_[index + 1], &r = nodes_[right];
    Node node;
    for (int a = 0; a < 3; ++a) {
        node.lo[a] = std::min(l.lo[a], r.lo[a]);
        node.hi[a] = std::max(l.hi[a], r.hi[a]);
    }
    node.first = right;
    node.count = 0;
    nodes_[index] = node;
    return index;
}

}  // namespace tpb
