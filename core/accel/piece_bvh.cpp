#include "accel/piece_bvh.h"

#include "base/parallel.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

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

}  // namespace

void PieceBvh::build(const std::vector<Box>& boxes, int threads) {
    constexpr size_t kChunk = size_t(1) << 14;
    const size_t n = boxes.size();
    order_.resize(n);
    nodeCount_ = 0;  // an empty hierarchy until the nodes are built (no box: none)
    leaves_.clear();
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
    // Sort keys: the code above the box's index (31 bits), so that one array is sorted and the
    // index comes with it; LSD radix sort of the code's 33 bits, 11 per pass: stable, so equal
    // codes keep index order.
    if (n >= (size_t(1) << 31)) throw std::length_error("PieceBvh: more than 2^31 boxes");
    keys_.resize(n);
    parallelChunks(n, threads, kChunk, [&](size_t i0, size_t i1) {
        for (size_t i = i0; i < i1; ++i) {
            uint64_t code = 0;
            for (int a = 0; a < 3; ++a) {
                const double c = 0.5 * (static_cast<double>(boxes[i].lo[a]) + boxes[i].hi[a]);
                const double q = std::clamp((c - lo[a]) * scale[a], 0.0, 2047.0);  // NaN -> 0 below
                code |= spread3(static_cast<uint64_t>(q >= 0.0 ? q : 0.0)) << a;
            }
            keys_[i] = (code << kIndexBits) | i;
        }
    });
    scratchKeys_.resize(n);
    for (int shift = kIndexBits; shift < kIndexBits + 33; shift += 11) {
        uint32_t count[2049] = {};
        for (size_t i = 0; i < n; ++i) ++count[((keys_[i] >> shift) & 0x7ffu) + 1];
        for (int b = 0; b < 2048; ++b) count[b + 1] += count[b];
        for (size_t i = 0; i < n; ++i) scratchKeys_[count[(keys_[i] >> shift) & 0x7ffu]++] = keys_[i];
        keys_.swap(scratchKeys_);
    }
    sorted_.resize(n);
    parallelChunks(n, threads, kChunk, [&](size_t i0, size_t i1) {
        for (size_t i = i0; i < i1; ++i) {
            order_[i] = static_cast<uint32_t>(keys_[i] & kIndexMask);
            sorted_[i] = boxes[order_[i]];
        }
    });
    // Every node has at least two children (a range of two or more boxes splits into two non-empty
    // halves), so n - 1 nodes suffice (one for a single box). Not value-initialised: buildNode sets
    // every field.
    if (n > nodeCapacity_) {
        nodes_.reset(new Node4[n]);
        nodeCapacity_ = n;
    }
    if (n == 1) {  // a root with one leaf slot
        nodeCount_ = 1;
        Node4& node = nodes_[0];
        node.interior = node.several = 0;
        node.single = 1;
        for (int j = 0; j < 4; ++j) {
            node.child[j] = 0;
            setSlot(node, j, j == 0 ? &sorted_[0] : nullptr);
        }
        return;
    }
    Box root = emptyBox();
    if (threads <= 1 || n < 2 * kChunk) {
        Builder serial{0, &leaves_};
        buildNode(0, static_cast<uint32_t>(n), 0, root, serial);
        nodeCount_ = serial.next;
        return;
    }
    // The root's interior children's subtrees are built at once, each into its own stretch of the
    // node array: a range of m boxes has at most m - 1 nodes, so subtree j starts after the
    // stretches of the ones before it (unused nodes may be left between them; none is referenced),
    // and its leaves of several boxes are appended to leaves_ afterwards, their indices shifted.
    const Split top = splitRange(0, static_cast<uint32_t>(n), 0);
    Node4& node = nodes_[0];
    beginNode(node);
    uint32_t start[4] = {}, next[4] = {};
    std::vector<Leaf> leaves[4];
    Box boxOf[4];
    uint32_t offset = 1;
    for (int j = 0; j < top.ranges; ++j) {
        start[j] = offset;
        if (!isLeaf(top, j, 0)) offset += top.r[j][1] - top.r[j][0] - 1;
    }
    parallelFor(top.ranges, threads, [&](int64_t jj, int) {
        const int j = static_cast<int>(jj);
        boxOf[j] = emptyBox();
        if (isLeaf(top, j, 0)) return;
        Builder sub{start[j], &leaves[j]};
        buildNode(top.r[j][0], top.r[j][1], 2, boxOf[j], sub);
        next[j] = sub.next;
    });
    nodeCount_ = 1;
    for (int j = 0; j < top.ranges; ++j) {
        if (isLeaf(top, j, 0)) continue;
        const uint32_t base = static_cast<uint32_t>(leaves_.size());
        leaves_.insert(leaves_.end(), leaves[j].begin(), leaves[j].end());
        for (uint32_t k = start[j]; k < next[j] && base > 0; ++k)
            for (unsigned m = nodes_[k].several; m; m &= m - 1) nodes_[k].child[__builtin_ctz(m)] += base;
        nodeCount_ = std::max<size_t>(nodeCount_, next[j]);
        node.child[j] = start[j];
        node.interior |= static_cast<uint8_t>(1u << j);
    }
    Builder rootLeaves{0, &leaves_};
    finishNode(node, top, 0, boxOf, rootLeaves, root);
}

static_assert(sizeof(PieceBvh::Box) == 24, "kAccelBytesPerPiece (beam_accel.h) counts 24-byte boxes");

void PieceBvh::setSlot(Node4& node, int j, const Box* box) {
    static_assert(sizeof(Node4) == 128, "the header and kAccelBytesPerPiece (beam_accel.h) count 128-byte nodes");
    for (int a = 0; a < 3; ++a) {
        if (!box) {  // unused: a box no segment meets (lo > hi on every axis)
            node.lo[a][j] = 1.0f;
            node.hi[a][j] = -1.0f;
            continue;
        }
        node.lo[a][j] = box->lo[a] - 1e-6f * (1.0f + std::abs(box->lo[a]));
        node.hi[a][j] = box->hi[a] + 1e-6f * (1.0f + std::abs(box->hi[a]));
    }
}

// Where the sorted range [begin, end) splits: where the highest bit in which its first and last
// codes differ turns on (one place, the codes being sorted), or the middle when they are equal.
uint32_t PieceBvh::splitOf(uint32_t begin, uint32_t end) const {
    const uint64_t first = keys_[begin] >> kIndexBits, last = keys_[end - 1] >> kIndexBits;
    if (first == last) return begin + (end - begin) / 2;
    const int bit = 63 - __builtin_clzll(first ^ last);
    const uint64_t mask = ~uint64_t(0) << (bit + kIndexBits);  // the shared prefix and the bit, in keys
    const uint64_t target = (last << kIndexBits) & mask;
    return static_cast<uint32_t>(std::lower_bound(keys_.begin() + begin, keys_.begin() + end, target,
                                                  [mask](uint64_t k, uint64_t t) { return (k & mask) < t; }) -
                                 keys_.begin());
}

// The split of the sorted range [begin, end) (at least two boxes) at `depth`: split twice (the
// binary LBVH's two levels at once) into up to four ranges.
PieceBvh::Split PieceBvh::splitRange(uint32_t begin, uint32_t end, int depth) const {
    Split s;
    const uint32_t mid = splitOf(begin, end);
    for (const auto& [b, e] : {std::pair<uint32_t, uint32_t>{begin, mid}, std::pair<uint32_t, uint32_t>{mid, end}}) {
        if (e - b >= 2 && depth + 1 < kMaxDepth) {
            const uint32_t m = splitOf(b, e);
            s.r[s.ranges][0] = b;
            s.r[s.ranges++][1] = m;
            s.r[s.ranges][0] = m;
            s.r[s.ranges++][1] = e;
        } else {
            s.r[s.ranges][0] = b;
            s.r[s.ranges++][1] = e;
        }
    }
    return s;
}

// Range j of a split at `depth` is a leaf slot: one box, or at the depth cap.
bool PieceBvh::isLeaf(const Split& s, int j, int depth) { return s.r[j][1] - s.r[j][0] == 1 || depth + 2 >= kMaxDepth; }

void PieceBvh::beginNode(Node4& node) { node.interior = node.single = node.several = 0; }

// The node's slots from its split: leaf slots made here, interior ones (already in node.child and
// node.interior) given their subtrees' boxes `childBox`; unused slots emptied. `bounds` gets the
// node's box.
void PieceBvh::finishNode(Node4& node, const Split& s, int depth, const Box (&childBox)[4], Builder& builder,
                          Box& bounds) const {
    bounds = emptyBox();
    for (int j = 0; j < 4; ++j) {
        if (j >= s.ranges) {
            node.child[j] = 0;
            setSlot(node, j, nullptr);
            continue;
        }
        Box c = childBox[j];
        const uint32_t b = s.r[j][0], e = s.r[j][1];
        if (isLeaf(s, j, depth)) {
            c = emptyBox();
            for (uint32_t k = b; k < e; ++k) grow(c, sorted_[k]);
            if (e - b == 1) {
                node.child[j] = b;
                node.single |= static_cast<uint8_t>(1u << j);
            } else {
                node.child[j] = static_cast<uint32_t>(builder.leaves->size());
                builder.leaves->push_back({b, e - b});
                node.several |= static_cast<uint8_t>(1u << j);
            }
        }
        grow(bounds, c);
        setSlot(node, j, &c);
    }
}

// The subtree over the sorted range [begin, end) (at least two boxes), its nodes taken from
// builder.next on (depth-first: this node first). Returns the node's index; `bounds` gets the
// range's box.
uint32_t PieceBvh::buildNode(uint32_t begin, uint32_t end, int depth, Box& bounds, Builder& builder) {
    const Split s = splitRange(begin, end, depth);
    const uint32_t index = builder.next++;
    Node4& node = nodes_[index];  // written in place (the array never moves during a build)
    beginNode(node);
    Box childBox[4];
    for (int j = 0; j < s.ranges; ++j) {
        if (isLeaf(s, j, depth)) continue;
        node.child[j] = buildNode(s.r[j][0], s.r[j][1], depth + 2, childBox[j], builder);
        node.interior |= static_cast<uint8_t>(1u << j);
    }
    finishNode(node, s, depth, childBox, builder, bounds);
    return index;
}

}  // namespace tpb
