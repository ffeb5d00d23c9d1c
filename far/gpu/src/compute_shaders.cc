#include "compute_shaders.h"

#include <initializer_list>
#include <string>

namespace far::internal {
namespace {

// The shader storage blocks, by binding (compute_shaders.h). Each kernel declares only those
// it uses: llvmpipe links at most 16 in a program.
constexpr const char* kBlocks[kNumBindings] = {
    "readonly buffer Positions { double pos[]; };",
    "readonly buffer Triangles { uint tri_vertex[]; };",
    "buffer TriBoxes { vec4 tri_box[]; };",
    "readonly buffer Nodes { uvec4 node[]; };",
    "readonly buffer Order { uint order[]; };",
    "buffer NodeBoxes { vec4 node_box[]; };",
    "buffer Work { uvec4 work[]; };",
    "buffer WorkStart { uint work_start[]; };",
    "buffer Counters { uint counters[]; };",
    "writeonly buffer Crossing { uvec4 crossing[]; };",
    "writeonly buffer Undecided { uvec4 undecided[]; };",
    "readonly buffer Ranges { uvec2 ranges[]; };",
    "readonly buffer RefitList { uint refit_list[]; };",
    "buffer PcsBits { uint pcs_bits[]; };",
    "readonly buffer PairBoxes { double pair_box[]; };",
    "readonly buffer Slots { uvec4 slot_info[]; };",
    "buffer ObjectPairs { uvec2 object_pair[]; };",
    "buffer Dispatch { uint dispatch[]; };",
    "buffer Candidates { uvec4 candidate[]; };",
    "readonly buffer Model { double model[]; };",
    "readonly buffer Placements { double placement[]; };",
};

// What every kernel shares.
constexpr const char* kCommon = R"(
uniform uint u_count;  // invocations with work: triangles or nodes

uint Stride() { return gl_NumWorkGroups.x * 64u; }
)";

constexpr const char* kVertex = R"(
dvec3 Vertex(uint v) { return dvec3(pos[3u * v], pos[3u * v + 1u], pos[3u * v + 2u]); }
)";

// A kernel's source: the version, the work group, `blocks`, the shared helpers, then `body`.
std::string Kernel(std::initializer_list<ComputeBinding> blocks, const std::string& body) {
  std::string text = "#version 450\nlayout(local_size_x = 64) in;\n";
  bool positions = false;
  for (ComputeBinding binding : blocks) {
    text += "layout(std430, binding = " + std::to_string(binding) + ") " + kBlocks[binding] + "\n";
    positions = positions || binding == kPositionsBinding;
  }
  text += kCommon;
  if (positions) text += kVertex;
  return text + body;
}

// The vertices of the posed objects that moved: placement[16 r, 16 r + 12) is object r's X_WM
// row by row, then its first vertex, its vertices and the invocations before it (integers below
// 2^32 in doubles: exact), u_placements objects in all. Every product and sum is rounded once,
// in far::WorldVertex's order: `precise` forbids fusing them into an fma or reordering them, and
// with IEEE binary64 arithmetic (which the fp64 filter assumes too; GLSL itself promises doubles
// only float's precision) add and mul are correctly rounded, so each position is the very double
// the CPU's exact predicates read. ComputeCollider checks that on the device before relying on it.
static_assert(kPositionsBinding == 0, "the placement kernel writes binding 0");
constexpr const char* kPlace = R"(
layout(std430, binding = 0) writeonly buffer PlacedPositions { double placed[]; };
uniform uint u_placements;
uniform double u_tiny;  // kTinyWorldCoordinate: smaller magnitudes are flushed to +0

void main() {
  for (uint item = gl_GlobalInvocationID.x; item < u_count; item += Stride()) {
    uint at = 16u * PlacementOf(item, u_placements);
    uint v = uint(placement[at + 12u]) + (item - uint(placement[at + 14u]));
    dvec3 p = dvec3(model[3u * v], model[3u * v + 1u], model[3u * v + 2u]);
    for (uint i = 0u; i < 3u; ++i) {
      precise double sum = placement[at + 4u * i] * p.x;
      sum = sum + placement[at + 4u * i + 1u] * p.y;
      sum = sum + placement[at + 4u * i + 2u] * p.z;
      sum = sum + placement[at + 4u * i + 3u];
      placed[3u * v + i] = abs(sum) < u_tiny ? 0.0LF : sum;
    }
  }
}
)";

constexpr const char* kTriangleBoxes = R"(
// A float <= x: x rounded, and one float step down when the rounding went up. The comparison is
// exact (a float is a double), so this holds whatever rounding the conversion used, as long as
// it is within one float step. -2^-126 stands below every negative x that rounded to zero (a
// device may flush subnormal floats to zero).
float FloatBelow(double x) {
  float f = float(x);
  if (double(f) > x) {
    if (f == 0.0) f = uintBitsToFloat(0x80800000u);
    else if (f > 0.0) f = uintBitsToFloat(floatBitsToUint(f) - 1u);
    else f = uintBitsToFloat(floatBitsToUint(f) + 1u);
  }
  return f;
}
float FloatAbove(double x) { return -FloatBelow(-x); }

// The triangles of the objects that moved: ranges[r] = (first global triangle, invocations
// before this range), u_ranges of them. Each box is stored at its triangle's place in the leaf
// order (an object's places are its own triangles' range): a leaf's boxes lie side by side.
uniform uint u_ranges;

void main() {
  for (uint item = gl_GlobalInvocationID.x; item < u_count; item += Stride()) {
    uint r = RangeOf(item, u_ranges);
    uint at = ranges[r].x + (item - ranges[r].y);
    uint t = order[at];
    dvec3 a = Vertex(tri_vertex[3u * t]);
    dvec3 b = Vertex(tri_vertex[3u * t + 1u]);
    dvec3 c = Vertex(tri_vertex[3u * t + 2u]);
    dvec3 lo = min(min(a, b), c);
    dvec3 hi = max(max(a, b), c);
    tri_box[2u * at] = vec4(FloatBelow(lo.x), FloatBelow(lo.y), FloatBelow(lo.z), 0.0);
    tri_box[2u * at + 1u] = vec4(FloatAbove(hi.x), FloatAbove(hi.y), FloatAbove(hi.z), 0.0);
  }
}
)";

// The object pairs, as far's SweepAndPrune finds them: two objects whose boxes, grown by half
// the margin each on the CPU, overlap closed on every axis. kPairBoxesBinding holds the boxes
// of the objects that pair at all, sorted by their low x (8 doubles each: lo xyz, the slot, hi
// xyz, 0). One box per invocation sweeps the boxes after it until one starts beyond its high
// x: O(n + pairs overlapping on x). Testing all n (n - 1) / 2 pairs instead cost llvmpipe 1.9 s
// a step at 10,000 objects (the sweep: 46-53 ms). Only comparisons of the same doubles: the same
// pairs on any device.
constexpr const char* kObjectPairs = R"(
uniform uint u_boxes;
uniform uint u_pair_capacity;

dvec3 Lo(uint p) { return dvec3(pair_box[8u * p], pair_box[8u * p + 1u], pair_box[8u * p + 2u]); }
dvec3 Hi(uint p) {
  return dvec3(pair_box[8u * p + 4u], pair_box[8u * p + 5u], pair_box[8u * p + 6u]);
}

void main() {
  for (uint p = gl_GlobalInvocationID.x; p < u_boxes; p += Stride()) {
    dvec3 lo = Lo(p);
    dvec3 hi = Hi(p);
    uint slot = uint(pair_box[8u * p + 3u]);
    for (uint q = p + 1u; q < u_boxes && pair_box[8u * q] <= hi.x; ++q) {
      if (any(greaterThan(Lo(q), hi)) || any(greaterThan(lo, Hi(q)))) continue;
      uint other = uint(pair_box[8u * q + 3u]);
      uint k = atomicAdd(counters[7], 1u);
      if (k < u_pair_capacity) object_pair[k] = uvec2(min(slot, other), max(slot, other));
      // else: counted; the host grows the buffer and runs again
    }
  }
}
)";

// The traversal's work, in one work group: per object pair p, work[2p] and work[2p + 1] (see
// kTraverse) and work_start[p], the driver triangles of the pairs before p (a pair with an
// object without hierarchy has none), then the traversal's indirect dispatch. Sums saturate at
// 2^32 - 1, which means too much work (counters[8]: the host refuses the step).
constexpr const char* kPairWork = R"(
uniform uint u_pair_capacity;
shared uint g_sums[64];

uint AddSaturated(uint a, uint b) { return a + b < a ? 0xffffffffu : a + b; }

// The work of pair p; returns its driver triangles.
uint WriteWork(uint p) {
  uvec2 ij = object_pair[p];
  uvec4 a = slot_info[ij.x];
  uvec4 b = slot_info[ij.y];
  bool a_drives = a.y <= b.y;
  uvec4 driver = a_drives ? a : b;
  uvec4 other = a_drives ? b : a;
  work[2u * p] = uvec4(driver.x, other.x, other.z, 0u);
  work[2u * p + 1u] = a_drives ? uvec4(ij.x, ij.y, 1u, 0u) : uvec4(ij.y, ij.x, 0u, 0u);
  return a.w == 0u || b.w == 0u ? 0u : driver.y;
}

void main() {
  uint pairs = min(counters[7], u_pair_capacity);
  uint lane = gl_LocalInvocationIndex;
  uint total = 0u;
  for (uint first = 0u; first < pairs; first += 64u) {
    uint p = first + lane;
    uint items = p < pairs ? WriteWork(p) : 0u;
    // An inclusive scan of the 64 lanes' items (Hillis and Steele).
    g_sums[lane] = items;
    barrier();
    for (uint step = 1u; step < 64u; step *= 2u) {
      uint add = lane >= step ? g_sums[lane - step] : 0u;
      barrier();
      g_sums[lane] = AddSaturated(g_sums[lane], add);
      barrier();
    }
    if (p < pairs) work_start[p] = AddSaturated(total, g_sums[lane] - items);
    total = AddSaturated(total, g_sums[63]);
    barrier();  // every lane has read g_sums before the next chunk writes it
  }
  if (lane == 0u) {
    bool overflow = total == 0xffffffffu;
    if (overflow) counters[8] = 1u;
    work_start[pairs] = total;
    dispatch[0] = overflow ? 0u : min(total / 64u + (total % 64u == 0u ? 0u : 1u), 65535u);
    dispatch[1] = 1u;
    dispatch[2] = 1u;
    dispatch[3] = total;
    dispatch[4] = pairs;
  }
}
)";

// One level of the hierarchies of the objects that moved, deepest level first: the nodes
// refit_list[u_first, u_first + u_count). A leaf's box is the union of its triangles' (at most
// 8), an inner node's the union of its children's, refit by the dispatch before.
constexpr const char* kRefit = R"(
uniform uint u_first;

void main() {
  for (uint i = gl_GlobalInvocationID.x; i < u_count; i += Stride()) {
    uint n = refit_list[u_first + i];
    uvec4 nd = node[n];
    vec3 lo;
    vec3 hi;
    if (nd.y == 0u) {
      lo = min(node_box[2u * nd.x].xyz, node_box[2u * nd.x + 2u].xyz);
      hi = max(node_box[2u * nd.x + 1u].xyz, node_box[2u * nd.x + 3u].xyz);
    } else {
      float inf = uintBitsToFloat(0x7f800000u);
      lo = vec3(inf);
      hi = vec3(-inf);
      for (uint k = nd.z; k < nd.w; ++k) {
        lo = min(lo, tri_box[2u * k].xyz);
        hi = max(hi, tri_box[2u * k + 1u].xyz);
      }
    }
    node_box[2u * n] = vec4(lo, 0.0);
    node_box[2u * n + 1u] = vec4(hi, 0.0);
  }
}
)";

// The traversal. Work entry of object pair p: work[2p] = (driver's first global triangle,
// partner's first global triangle, partner's root node, 0), work[2p + 1] = (driver's slot,
// partner's slot, 1 when the driver is the pair's object_a, 0). Every invocation takes one
// triangle of a driver and descends the partner's hierarchy with it, appending each triangle
// pair whose boxes meet to the candidates as (slot_a, triangle_a, slot_b, triangle_b),
// triangles local to their objects. Boxes only: the filters run in their own kernel (kFilter),
// one pair per invocation. Inside the descent an invocation's pairs were filtered one after
// another while the rest of its SIMD group waited, and the filters' registers limited how many
// descents a GPU core kept in flight (paper-leaves: 1.55 pairs per driver triangle on average,
// 8 or more for a tenth of them).
constexpr const char* kTraverse = R"(
uniform float u_slack;  // triangle boxes within this on every axis meet (0: share a point)
uniform uint u_candidate_capacity;  // entries of the candidates' buffer

bool Apart(vec3 alo, vec3 ahi, vec3 blo, vec3 bhi) {
  return any(greaterThan(blo - ahi, vec3(u_slack))) || any(greaterThan(alo - bhi, vec3(u_slack)));
}

// The pairs of the driver's triangle at leaf-order place `driver` with the triangles at places
// first + k for the bits k of `hits`, appended with one atomic for all of them.
void AppendCandidates(uint driver, uint first, uint hits, uvec4 w0, uvec4 w1) {
  uint at = atomicAdd(counters[2], uint(bitCount(hits)));
  uint a = order[driver] - w0.x;
  for (; hits != 0u; hits &= hits - 1u, ++at) {
    if (at >= u_candidate_capacity) return;  // counted: the host grows the buffer and runs again
    uint b = order[first + uint(findLSB(hits))] - w0.y;
    candidate[at] = w1.z != 0u ? uvec4(w1.x, a, w1.y, b) : uvec4(w1.y, b, w1.x, a);
  }
}

// Each invocation's traversal stack, in shared memory: as a private array (uint stack[64]),
// llvmpipe (Mesa 22.3) ran the descent wrong, dropping and repeating nodes, where the same
// data descended on the CPU found every pair (ComputeColliderTest caught it).
shared uint g_stacks[64 * 64];

bool Meets(vec3 tlo, vec3 thi, uint n) {
  return !Apart(tlo, thi, node_box[2u * n].xyz, node_box[2u * n + 1u].xyz);
}

void main() {
  uint base = gl_LocalInvocationIndex * 64u;
  uint count = dispatch[3];  // driver triangles, and the object pairs, from kPairWork
  uint pairs = dispatch[4];
  for (uint item = gl_GlobalInvocationID.x; item < count; item += Stride()) {
    // The object pair: the last p with work_start[p] <= item.
    uint lo = 0u;
    uint hi = pairs;
    while (hi - lo > 1u) {
      uint mid = (lo + hi) / 2u;
      if (work_start[mid] <= item) lo = mid;
      else hi = mid;
    }
    uvec4 w0 = work[2u * lo];
    uvec4 w1 = work[2u * lo + 1u];
    // The driver's triangles, in their leaf order (where their boxes are).
    uint driver = w0.x + (item - work_start[lo]);
    vec3 tlo = tri_box[2u * driver].xyz;
    vec3 thi = tri_box[2u * driver + 1u].xyz;
    if (!Meets(tlo, thi, w0.z)) continue;
    // Every node n reached meets the driver's box. An inner node tests both children (their
    // boxes lie side by side) and goes on into one that meets, keeping the other on the stack
    // when both do: fewer stack reads and writes and loop turns than testing each node as it
    // came off the stack (paper-leaves popped 13 nodes per driver triangle that way).
    uint n = w0.z;
    uint top = 0u;
    for (;;) {
      uvec4 nd = node[n];
      if (nd.y == 0u) {
        bool left = Meets(tlo, thi, nd.x);
        bool right = Meets(tlo, thi, nd.x + 1u);
        if (left && right) {
          if (top == 64u) {
            atomicOr(counters[5], 1u);
            break;
          }
          g_stacks[base + top] = nd.x + 1u;
          top += 1u;
        }
        if (left || right) {
          n = left ? nd.x : nd.x + 1u;
          continue;
        }
      } else {
        // A leaf: its triangles whose boxes meet the driver's, 32 at a time.
        for (uint first = nd.z; first < nd.w; first += 32u) {
          uint hits = 0u;
          for (uint k = first; k < min(nd.w, first + 32u); ++k) {
            if (!Apart(tlo, thi, tri_box[2u * k].xyz, tri_box[2u * k + 1u].xyz))
              hits |= 1u << (k - first);
          }
          if (hits != 0u) AppendCandidates(driver, first, hits, w0, w1);
        }
      }
      if (top == 0u) break;
      top -= 1u;
      n = g_stacks[base + top];
    }
  }
}
)";

// The filters' dispatch, one invocation: a work group per 64 candidates the traversal wrote.
constexpr const char* kFilterDispatch = R"(
uniform uint u_candidate_capacity;

void main() {
  if (gl_GlobalInvocationID.x != 0u) return;
  uint n = min(counters[2], u_candidate_capacity);
  dispatch[5] = min(n / 64u + (n % 64u == 0u ? 0u : 1u), 65535u);
  dispatch[6] = 1u;
  dispatch[7] = 1u;
  dispatch[8] = n;
}
)";

// The filters, one candidate pair per invocation.
//
// The filters classify a triangle pair as the exact predicates would (far/geometry's
// TrianglesIntersect, Guigue and Devillers' orientation tests) from orientation signs that their
// error bounds certify; where a sign is not certified, the pair is undecided. Every sign is
// Orient3d(a, b, c, d) = ((b - a) x (c - a)) . (d - a), evaluated as far's PlaneSide evaluates it.
// Float: the differences in double, rounded to float (each within 2^-23 of itself, relative),
// then float products and sums; |error| <= 2^-20 P + 2^-84 where P is the permanent computed
// alongside, as long as every nonzero difference lies in [2^-40, 2^40] (else: not certified).
// Double: |error| <= 8 2^-53 P + 2^-970 (Shewchuk's orient3d bound, (7 + 56 eps) eps, rounded
// up, plus what flushing subnormal results to zero may lose). docs/culling.md has the argument.
constexpr const char* kFilter = R"(
uniform uint u_capacity;  // entries of each output buffer
// FAR_DISTANCE (defined before this, 0 or 1: two programs): a distance query, where every pair
// within the slack goes to the CPU unless proven farther than it would accept beside this D.
#if FAR_DISTANCE
uniform double u_max_distance;
#endif

const int kApart = 0;
const int kCross = 1;
const int kUndecided = 2;

// 0 or a magnitude in [2^-40, 2^40]: the float filter's products neither overflow nor leave
// the normal range.
bool FloatSafe(dvec3 v) {
  double lo = double(uintBitsToFloat(0x2b800000u));  // 2^-40
  double hi = double(uintBitsToFloat(0x53800000u));  // 2^40
  dvec3 m = abs(v);
  bvec3 ok = bvec3((m.x == 0.0LF || (m.x >= lo && m.x <= hi)),
                   (m.y == 0.0LF || (m.y >= lo && m.y <= hi)),
                   (m.z == 0.0LF || (m.z >= lo && m.z <= hi)));
  return all(ok);
}

// The sign of Orient3d(a, b, c, d) where the float evaluation certifies it, else 0.
int SideFloat(dvec3 a, dvec3 b, dvec3 c, dvec3 d) {
  precise dvec3 de = b - a;
  precise dvec3 df = c - a;
  precise dvec3 dw = d - a;
  if (!FloatSafe(de) || !FloatSafe(df) || !FloatSafe(dw)) return 0;
  vec3 e = vec3(de);
  vec3 f = vec3(df);
  vec3 w = vec3(dw);
  precise float p0 = e.y * f.z;
  precise float p1 = e.z * f.y;
  precise float p2 = e.z * f.x;
  precise float p3 = e.x * f.z;
  precise float p4 = e.x * f.y;
  precise float p5 = e.y * f.x;
  precise float det = w.x * (p0 - p1) + w.y * (p2 - p3) + w.z * (p4 - p5);
  precise float perm = abs(w.x) * (abs(p0) + abs(p1)) + abs(w.y) * (abs(p2) + abs(p3)) +
                       abs(w.z) * (abs(p4) + abs(p5));
  precise float bound = perm * uintBitsToFloat(0x35800000u) + uintBitsToFloat(0x15800000u);
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return 0;
}

// The sign of Orient3d(a, b, c, d) where the fp64 evaluation certifies it, else 0.
int SideDouble(dvec3 a, dvec3 b, dvec3 c, dvec3 d) {
  precise dvec3 e = b - a;
  precise dvec3 f = c - a;
  precise dvec3 w = d - a;
  precise double p0 = e.y * f.z;
  precise double p1 = e.z * f.y;
  precise double p2 = e.z * f.x;
  precise double p3 = e.x * f.z;
  precise double p4 = e.x * f.y;
  precise double p5 = e.y * f.x;
  precise double det = w.x * (p0 - p1) + w.y * (p2 - p3) + w.z * (p4 - p5);
  precise double perm = abs(w.x) * (abs(p0) + abs(p1)) + abs(w.y) * (abs(p2) + abs(p3)) +
                        abs(w.z) * (abs(p4) + abs(p5));
  double rel = ldexp(1.0lf, -50);    // 8 * 2^-53
  double tiny = ldexp(1.0lf, -970);
  precise double bound = perm * rel + tiny;
  if (det > bound) return 1;
  if (-det > bound) return -1;
  return 0;
}
// x[k] by constant indices. NVIDIA's compiler (driver 580.159) kept dvec3 arrays filled in a
// loop over an int at float precision (see kFilter's main); whether reads at a variable index
// lose precision too was not measured, so no kernel makes one.
dvec3 Corner(dvec3 x[3], int k) { return k == 0 ? x[0] : (k == 1 ? x[1] : x[2]); }

$CLASSIFY_FLOAT
$CLASSIFY_DOUBLE

#if FAR_DISTANCE
// A distance query's cut. The CPU's TriangleDistanceIfWithin(s, t, D) accepts a pair only when
// its distance d satisfies d <= D + 288 eps L (L: the diagonal of the six vertices' box, eps =
// 2^-53: its slack of 256 eps L and its distance's underestimate of at most 32 eps L;
// far/geometry/src/triangle_distance.cc). A pair proven farther than that is dropped here, by
// the CPU's own lower bounds evaluated in fp64: the boxes' gap along an axis, and the gap
// between the projections onto the triangles' normals, the line between their centroids and
// the nine cross products of an edge of each. L1 = the box's extents summed, rounded up, stands
// for L (L1 >= L). docs/culling.md has the argument.
//
// The gap of the two triangles' projections onto axis n proves d > `limit` - 64 eps L1 (see
// GapExceeds in triangle_distance.cc: the projections' rounding costs at most 8.02 eps |n| L),
// compared without a square root: gap^2 > |n|^2 limit^2 (1 + 2^-46), the margin 128 roundings
// of 2^-53 for the few made in squaring. An axis too short to square (|n|^2 < 2^-900, or a gap
// that small, where a device that flushes subnormals loses precision) or one that overflows
// proves nothing.
bool GapShowsFar(dvec3 n, dvec3 sb, dvec3 sc, dvec3 ta, dvec3 tb, dvec3 tc, double limit) {
  double tiny = ldexp(1.0lf, -900);
  precise double length2 = dot(n, n);
  if (!(length2 >= tiny) || isinf(length2)) return false;
  precise double s1 = dot(n, sb);
  precise double s2 = dot(n, sc);
  precise double t0 = dot(n, ta);
  precise double t1 = dot(n, tb);
  precise double t2 = dot(n, tc);
  double s_lo = min(0.0lf, min(s1, s2));
  double s_hi = max(0.0lf, max(s1, s2));
  double t_lo = min(t0, min(t1, t2));
  double t_hi = max(t0, max(t1, t2));
  precise double gap = max(t_lo - s_hi, s_lo - t_hi);
  if (!(gap >= tiny)) return false;
  precise double gap2 = gap * gap;
  precise double bound2 = length2 * (limit * limit) * (1.0lf + ldexp(1.0lf, -46));
  return !isinf(gap2) && gap2 > bound2;
}

// Whether the CPU's distance test would reject the pair, proven (then it need not go there).
bool FartherThanTheCpuAccepts(dvec3 s[3], dvec3 t[3]) {
  double eps = ldexp(1.0lf, -53);
  double margin = 1.0lf + ldexp(1.0lf, -46);
  dvec3 s_lo = min(min(s[0], s[1]), s[2]);
  dvec3 s_hi = max(max(s[0], s[1]), s[2]);
  dvec3 t_lo = min(min(t[0], t[1]), t[2]);
  dvec3 t_hi = max(max(t[0], t[1]), t[2]);
  precise dvec3 extent = max(s_hi, t_hi) - min(s_lo, t_lo);
  precise double l1 = (extent.x + extent.y + extent.z) * margin;
  precise double far_limit = u_max_distance + 288.0lf * eps * l1;
  // The boxes' gap along a coordinate axis: a lower bound of d, rounded by one subtraction.
  precise dvec3 gaps = max(t_lo - s_hi, s_lo - t_hi);
  if (max(gaps.x, max(gaps.y, gaps.z)) > far_limit * margin) return true;
  precise double axis_limit = far_limit + 64.0lf * eps * l1;
  precise dvec3 sb = s[1] - s[0];
  precise dvec3 sc = s[2] - s[0];
  precise dvec3 ta = t[0] - s[0];
  precise dvec3 tb = t[1] - s[0];
  precise dvec3 tc = t[2] - s[0];
  if (GapShowsFar(cross(sb, sc), sb, sc, ta, tb, tc, axis_limit)) return true;
  if (GapShowsFar(cross(tb - ta, tc - ta), sb, sc, ta, tb, tc, axis_limit)) return true;
  if (GapShowsFar(ta + tb + tc - sb - sc, sb, sc, ta, tb, tc, axis_limit)) return true;
  // The nine edge pairs, unrolled (no array: see the traversal's stack below).
  precise dvec3 s1 = sc - sb;
  precise dvec3 t0 = tb - ta;
  precise dvec3 t1 = tc - tb;
  precise dvec3 t2 = tc - ta;
  return GapShowsFar(cross(sb, t0), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(sb, t1), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(sb, t2), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(s1, t0), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(s1, t1), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(s1, t2), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(sc, t0), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(sc, t1), sb, sc, ta, tb, tc, axis_limit) ||
         GapShowsFar(cross(sc, t2), sb, sc, ta, tb, tc, axis_limit);
}
#endif

void Append(bool to_crossing, uvec4 entry) {
  uint i = atomicAdd(counters[to_crossing ? 0 : 1], 1u);
  if (i >= u_capacity) return;  // counted: the host grows the buffers and runs again
  if (to_crossing) crossing[i] = entry;
  else undecided[i] = entry;
}

// The work group's decided counts (float, fp64, distance culled), one global atomic each.
shared uint g_counts[3];

// Each candidate (slot_a, triangle_a, slot_b, triangle_b) is classified, then appended where it
// belongs as it is; an undecided entry of a distance query has bit 31 of slot_b set when the
// filters proved the two apart (the CPU then computes only the distance).
void main() {
  uint lane = gl_LocalInvocationIndex;
  if (lane < 3u) g_counts[lane] = 0u;
  barrier();
  uint float_decided = 0u;
  uint double_decided = 0u;
  uint distance_culled = 0u;
  uint count = dispatch[8];  // from kFilterDispatch
  for (uint i = gl_GlobalInvocationID.x; i < count; i += Stride()) {
    uvec4 entry = candidate[i];
    uint ta = slot_info[entry.x].x + entry.y;
    uint tb = slot_info[entry.z].x + entry.w;
    // Each corner by a constant index, not in a loop: NVIDIA's compiler (driver 580.159, on an
    // H200) kept dvec3 array elements filled in a loop over an int at float precision, and the
    // filters then certified wrong signs (the self-check and the hair-off-a-plane tests failed).
    dvec3 s[3];
    dvec3 t[3];
    s[0] = Vertex(tri_vertex[3u * ta]);
    s[1] = Vertex(tri_vertex[3u * ta + 1u]);
    s[2] = Vertex(tri_vertex[3u * ta + 2u]);
    t[0] = Vertex(tri_vertex[3u * tb]);
    t[1] = Vertex(tri_vertex[3u * tb + 1u]);
    t[2] = Vertex(tri_vertex[3u * tb + 2u]);
    int c = ClassifyFloat(s, t);
    if (c != kUndecided) {
      ++float_decided;
    } else {
      c = ClassifyDouble(s, t);
      if (c != kUndecided) ++double_decided;
    }
#if !FAR_DISTANCE
    if (c == kApart) continue;
#endif
    // Both triangles are in the primitive PCS: a bit each, read back instead of the CPU sorting
    // the pairs' triangles.
    atomicOr(pcs_bits[ta >> 5], 1u << (ta & 31u));
    atomicOr(pcs_bits[tb >> 5], 1u << (tb & 31u));
#if FAR_DISTANCE
    if (c == kApart && FartherThanTheCpuAccepts(s, t)) {
      ++distance_culled;
      continue;
    }
#endif
    if (c == kApart) entry.z |= 0x80000000u;
    Append(c == kCross, entry);
  }
  atomicAdd(g_counts[0], float_decided);
  atomicAdd(g_counts[1], double_decided);
  atomicAdd(g_counts[2], distance_culled);
  barrier();
  if (lane == 0u && g_counts[0] + g_counts[1] + g_counts[2] != 0u) {
    atomicAdd(counters[3], g_counts[0]);
    atomicAdd(counters[4], g_counts[1]);
    atomicAdd(counters[6], g_counts[2]);
  }
}
)";

// Guigue and Devillers' test on certified signs, as far/geometry's IntersectAfterBoxTest runs
// it on exact ones: kApart or kCross only where every sign it needs is certified. $SIDE is
// SideFloat or SideDouble.
constexpr const char* kClassify = R"(
int $NAME(dvec3 s[3], dvec3 t[3]) {
  // s's vertices against t's plane, and t's against s's.
  int sig0 = $SIDE(t[0], t[1], t[2], s[0]);
  int sig1 = $SIDE(t[0], t[1], t[2], s[1]);
  int sig2 = $SIDE(t[0], t[1], t[2], s[2]);
  if (sig0 != 0 && sig0 == sig1 && sig1 == sig2) return kApart;
  int tau0 = $SIDE(s[0], s[1], s[2], t[0]);
  int tau1 = $SIDE(s[0], s[1], s[2], t[1]);
  int tau2 = $SIDE(s[0], s[1], s[2], t[2]);
  if (tau0 != 0 && tau0 == tau1 && tau1 == tau2) return kApart;
  if (sig0 * sig1 * sig2 == 0 || tau0 * tau1 * tau2 == 0) return kUndecided;
  // General position, every sign certified and nonzero: each triangle has one vertex (the
  // apex) on its own side of the other's plane.
  int is = sig0 != sig1 && sig0 != sig2 ? 0 : (sig1 != sig0 && sig1 != sig2 ? 1 : 2);
  int it = tau0 != tau1 && tau0 != tau2 ? 0 : (tau1 != tau0 && tau1 != tau2 ? 1 : 2);
  int eps_s = is == 0 ? sig0 : (is == 1 ? sig1 : sig2);
  int eps_t = it == 0 ? tau0 : (it == 1 ? tau1 : tau2);
  dvec3 v = Corner(s, is);
  dvec3 w1 = Corner(s, (is + 1) % 3);
  dvec3 w2 = Corner(s, (is + 2) % 3);
  dvec3 u = Corner(t, it);
  dvec3 z1 = Corner(t, (it + 1) % 3);
  dvec3 z2 = Corner(t, (it + 2) % 3);
  if (eps_t < 0) { dvec3 x = w1; w1 = w2; w2 = x; }
  if (eps_s < 0) { dvec3 x = z1; z1 = z2; z2 = x; }
  // They meet iff Orient3d(v, w1, u, z1) <= 0 and Orient3d(v, w2, u, z2) >= 0.
  int r1 = $SIDE(v, w1, u, z1);
  if (r1 > 0) return kApart;
  int r2 = $SIDE(v, w2, u, z2);
  if (r2 < 0) return kApart;
  if (r1 < 0 && r2 > 0) return kCross;
  return kUndecided;
}
)";

void ReplaceAll(std::string& text, const std::string& from, const std::string& to) {
  for (size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
    text.replace(at, from.size(), to);
}

std::string Classify(const std::string& name, const std::string& side) {
  std::string text = kClassify;
  ReplaceAll(text, "$NAME", name);
  ReplaceAll(text, "$SIDE", side);
  return text;
}

// The GLSL function `uint NAME(uint item, uint count)`: the last of `count` entries whose first
// invocation (FIRST, of entry `mid`) is at most `item` (entry 0's is 0), by bisection.
std::string LastStartingBy(const std::string& name, const std::string& first) {
  std::string text = R"(
uint NAME(uint item, uint count) {
  uint r = 0u;
  uint past = count;
  while (past - r > 1u) {
    uint mid = (r + past) / 2u;
    if (FIRST <= item) r = mid;
    else past = mid;
  }
  return r;
}
)";
  ReplaceAll(text, "NAME", name);
  ReplaceAll(text, "FIRST", first);
  return text;
}

}  // namespace

std::string PlaceSource() {
  return Kernel({kModelBinding, kPlacementsBinding},
                LastStartingBy("PlacementOf", "uint(placement[16u * mid + 14u])") + kPlace);
}

std::string TriangleBoxesSource() {
  return Kernel(
      {kPositionsBinding, kTrianglesBinding, kTriBoxesBinding, kOrderBinding, kRangesBinding},
      LastStartingBy("RangeOf", "ranges[mid].y") + kTriangleBoxes);
}

std::string RefitSource() {
  return Kernel({kTriBoxesBinding, kNodesBinding, kNodeBoxesBinding, kRefitListBinding}, kRefit);
}

std::string ObjectPairsSource() {
  return Kernel({kPairBoxesBinding, kCountersBinding, kObjectPairsBinding}, kObjectPairs);
}

std::string PairWorkSource() {
  return Kernel({kObjectPairsBinding, kSlotsBinding, kWorkBinding, kWorkStartBinding,
                 kCountersBinding, kDispatchBinding},
                kPairWork);
}

std::string TraverseSource() {
  return Kernel({kTriBoxesBinding, kNodesBinding, kOrderBinding, kNodeBoxesBinding, kWorkBinding,
                 kWorkStartBinding, kCountersBinding, kDispatchBinding, kCandidatesBinding},
                kTraverse);
}

std::string FilterDispatchSource() {
  return Kernel({kCountersBinding, kDispatchBinding}, kFilterDispatch);
}

std::string FilterSource(bool distance) {
  std::string text = Kernel(
      {kPositionsBinding, kTrianglesBinding, kSlotsBinding, kCountersBinding, kCrossingBinding,
       kUndecidedBinding, kPcsBitsBinding, kDispatchBinding, kCandidatesBinding},
      std::string("#define FAR_DISTANCE ") + (distance ? "1" : "0") + "\n" + kFilter);
  ReplaceAll(text, "$CLASSIFY_FLOAT", Classify("ClassifyFloat", "SideFloat"));
  ReplaceAll(text, "$CLASSIFY_DOUBLE", Classify("ClassifyDouble", "SideDouble"));
  return text;
}

}  // namespace far::internal
