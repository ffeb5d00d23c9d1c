#include "far/gpu/compute_collider.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <thread>
#include <tuple>
#include <type_traits>
#include <utility>

#include "compute_shaders.h"
#include "gl_program.h"
#include "gl_timer.h"
#include "placement_probe.h"
#include <epoxy/gl.h>

#include "far/base/timer_slack.h"
#include "far/gpu/gl_lock.h"
#include "far/model/world_vertex.h"

namespace far {

using internal::CheckGl;

namespace {

static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "world vertices upload as they lie");

// Entries per buffer of triangle pairs (the candidates, the crossing and the undecided ones) at
// first, and at most (16 bytes each): a step with more triangle pairs whose boxes meet than the
// most is refused (the bvh method answers it).
constexpr size_t kFirstCapacity = size_t{1} << 16;
constexpr size_t kMostCapacity = size_t{1} << 25;
// Object pairs at first and at most (40 bytes each with their work): a step with more is
// refused (the bvh method answers it).
constexpr size_t kFirstPairCapacity = size_t{1} << 12;
constexpr size_t kMostPairCapacity = size_t{1} << 22;

using Clock = std::chrono::steady_clock;

// A buffer that overflowed holding `needed` entries grows to this: half as many again, to a
// power of two, at most `most` (@pre needed <= most). A scene whose count creeps up (contacts
// growing as cloths settle) would otherwise run the kernels twice each time it passed a power of
// two: scaling-1000000's 285,378 pairs whose boxes met, at a step after 222,959 had grown the
// buffer to 2^18.
size_t GrownCapacity(size_t needed, size_t most) {
  return std::min(std::bit_ceil(needed + needed / 2), most);
}

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// A fence after the GL work issued so far, flushed so that the GPU has that work now.
GLsync FenceAndFlush() {
  GLsync fence = glFenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  glFlush();
  return fence;
}

// Waits for `fence`, then deletes it, polling between short sleeps: NVIDIA's driver spins a core
// while a blocking wait waits (the gpu step's CPU time was its wall time on the H100), and on
// shared cores the simulators want that core. The sleeps run with 1 us of timer slack: with
// Linux's default 50 us, a 20 us sleep took 109 us (median, CI machine; 46 us with 1 us of
// slack), up to 90 us late against a step the goal holds to 500. A null fence (glFenceSync
// failed) waits with glFinish: the mapped read-back has no wait of its own.
void WaitAndDelete(GLsync fence) {
  if (fence == nullptr) {
    glFinish();
    return;
  }
  if (glClientWaitSync(fence, 0, 0) == GL_TIMEOUT_EXPIRED) {
    const ScopedTimerSlack slack(1000);
    while (glClientWaitSync(fence, 0, 0) == GL_TIMEOUT_EXPIRED)
      std::this_thread::sleep_for(std::chrono::microseconds(20));
  }
  glDeleteSync(fence);
}

// Work groups per dispatch: each invocation loops with the grid's stride past this.
GLuint Groups(size_t invocations) {
  const size_t groups =
      (invocations + internal::kComputeGroupSize - 1) / internal::kComputeGroupSize;
  return static_cast<GLuint>(std::clamp<size_t>(groups, 1, 65535));
}

// Whether an object has a pair box, not empty and without NaN: the others pair with nothing.
bool PairsAtAll(const ComputeObject& object) {
  const Eigen::AlignedBox3d& box = object.pair_box;
  return !object.p_WV.empty() && !box.isEmpty() && !box.min().hasNaN() && !box.max().hasNaN();
}

// The least float >= x (x >= 0 and finite).
float FloatAtLeast(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

// A shader storage buffer that grows (its contents are lost when it does). A read-back buffer
// lies in the client's memory, mapped for good: the CPU reads what the GPU wrote there once
// the step's fence has passed, with no driver call and no copy of the driver's own (on the
// H200, waiting and four glGetNamedBufferSubData took 0.2 ms above the kernels' 0.24).
struct Buffer {
  GLuint id = 0;
  size_t bytes = 0;
  bool read_back = false;
  const void* mapped = nullptr;  // a read-back buffer's contents; null if its mapping failed
  void Reserve(size_t wanted) {
    wanted = std::max<size_t>(wanted, 16);
    if (wanted <= bytes) return;
    // A multiple of 16 bytes: glClearNamedBufferData with GL_R32UI refuses a size that is not a
    // multiple of 4 (GL_INVALID_VALUE), and growing by half could make one.
    bytes = (std::max(wanted, bytes * 3 / 2) + 15) / 16 * 16;
    if (!read_back) {
      glNamedBufferData(id, static_cast<GLsizeiptr>(bytes), nullptr, GL_DYNAMIC_DRAW);
      return;
    }
    // Immutable storage cannot grow: a new buffer (deleting the old one unmaps it).
    glDeleteBuffers(1, &id);
    glCreateBuffers(1, &id);
    constexpr GLbitfield kMap = GL_MAP_READ_BIT | GL_MAP_PERSISTENT_BIT | GL_MAP_COHERENT_BIT;
    glNamedBufferStorage(id, static_cast<GLsizeiptr>(bytes), nullptr, kMap | GL_CLIENT_STORAGE_BIT);
    mapped = glMapNamedBufferRange(id, 0, static_cast<GLsizeiptr>(bytes), kMap);
  }
  template <typename T>
  const T* At(size_t offset) const {
    return reinterpret_cast<const T*>(static_cast<const char*>(mapped) + offset);
  }
};

// Where each slot's data lies in the global arrays.
struct SlotLayout {
  uint32_t vertex_base = 0, triangle_base = 0, node_base = 0;
  uint32_t triangles = 0, nodes = 0;
  uint64_t topology_key = 0;
  uint64_t world_key = 0;                     // uploaded; 0: not yet
  uint64_t model_key = 0;                     // p_MV in the model buffer; 0: not there
  std::vector<std::vector<uint32_t>> levels;  // global node indices by depth (root: 0)
};

Result<GLuint> CompileCompute(const std::string& source, const char* what) {
  auto program = internal::LinkComputeProgram(source);
  if (!program) {
    return MakeError(ErrorCode::kInternal, std::string("gpu method: the ") + what +
                                               " kernel: " + program.error().message);
  }
  return program;
}

}  // namespace

struct ComputeCollider::Impl {
  GLuint place_program = 0, boxes_program = 0, refit_program = 0, pairs_program = 0,
         work_program = 0;
  GLuint traverse_program = 0, filter_dispatch_program = 0;
  // The filters: [0] for contact queries, [1] for distance queries (FilterSource).
  struct FilterKernel {
    GLuint program = 0;
    GLint capacity = -1, max_distance = -1;
  };
  std::array<FilterKernel, 2> filter;
  std::array<Buffer, internal::kNumBindings> buffers;
  // A read-back buffer the step's last commands copy into: the counters, then the object pairs
  // (the whole capacity: how many there are only the GPU knows then), then the PCS bits. The
  // crossing and undecided pairs need no copy: those buffers are read-back buffers themselves,
  // which the filters write once per pair.
  Buffer copies{0, 0, true, nullptr};
  static constexpr size_t kPairsOffset = 64;  // after the counters
  size_t BitsOffset() const { return kPairsOffset + pair_capacity * 8; }
  std::vector<SlotLayout> layout;
  uint32_t total_vertices = 0, total_triangles = 0, total_nodes = 0;
  size_t capacity = kFirstCapacity;            // crossing and undecided entries
  size_t candidate_capacity = kFirstCapacity;  // triangle pairs whose boxes meet
  size_t pair_capacity = kFirstPairCapacity;
  size_t num_pair_boxes = 0;             // uploaded by UploadPairBoxes
  std::vector<Eigen::Vector3d> staging;  // the vertices of one upload
  std::vector<size_t> moved;             // slots whose vertices this step uploaded or placed
  // The posed objects this step places on the GPU (the placement kernel's entries), and their
  // vertices in all; whether the device places them exactly (PlacesOnGpu).
  std::vector<std::array<double, 16>> placements;
  uint32_t placed_vertices = 0;
  bool places_exactly = false;
  // The refit's work for one set of moved slots, on the GPU already (kRangesBinding,
  // kRefitListBinding): a scene whose same objects move every step (deforming leaves, cloth)
  // builds and uploads it once, until the set or the layout changes.
  struct RefitPlan {
    std::vector<size_t> moved;  // empty: no plan
    uint32_t triangles = 0;     // of the moved slots
    uint32_t ranges = 0;
    std::vector<size_t> begin, end;  // level d's nodes: list[begin[d], end[d])
  };
  RefitPlan refit_plan;
  // Uniform locations, looked up once.
  GLint place_count = -1, place_placements = -1, place_tiny = -1;
  GLint boxes_count = -1, boxes_ranges = -1, refit_count = -1, refit_first = -1;
  GLint pairs_boxes = -1, pairs_capacity = -1, work_capacity = -1;
  GLint traverse_slack = -1, traverse_capacity = -1, filter_dispatch_capacity = -1;
  // GL_TIME_ELAPSED queries: uploads, boxes and refit; object pairs and traversal; filters.
  GLuint refit_query = 0, traverse_query = 0, filter_query = 0;

  Buffer& buffer(internal::ComputeBinding binding) { return buffers[binding]; }
  // Binds every buffer to its binding, whole, in one call (GL 4.4's multi-bind: a call per
  // buffer was 19 driver calls, twice a step).
  void BindBuffers() {
    std::array<GLuint, internal::kNumBindings> ids;
    for (size_t binding = 0; binding < buffers.size(); ++binding)
      ids[binding] = buffers[binding].id;
    glBindBuffersBase(GL_SHADER_STORAGE_BUFFER, 0, static_cast<GLsizei>(ids.size()), ids.data());
  }
  // Grows `binding`'s buffer to hold `bytes` and uploads them to its start; returns the bytes.
  int64_t Upload(internal::ComputeBinding binding, const void* data, size_t bytes) {
    buffer(binding).Reserve(bytes);
    if (bytes > 0)
      glNamedBufferSubData(buffer(binding).id, 0, static_cast<GLsizeiptr>(bytes), data);
    return static_cast<int64_t>(bytes);
  }
  Result<int64_t> EnsureLayout(std::span<const ComputeObject> objects);
  int64_t UploadVertices(std::span<const ComputeObject> objects);
  // The model buffer for `vertices` (a new layout's), if any of `objects` is posed. Reserved
  // only with a new layout, where every slot's model_key starts again at 0 (a buffer that grows
  // loses what it held): an object posed later, beyond what the buffer holds, is uploaded as its
  // world vertices until the layout changes.
  void ReserveModel(std::span<const ComputeObject> objects, size_t vertices);
  // Adds `object` (posed, in slot `at`) to this step's placements, uploading its own vertices
  // first when the model buffer does not hold them; returns the bytes uploaded.
  int64_t AddPlacement(SlotLayout& at, const ComputeObject& object);
  // Whether `object` (in slot `at`) is placed on the GPU: posed, on a device that places
  // exactly, with room for its own vertices in the model buffer.
  bool Placeable(const SlotLayout& at, const ComputeObject& object) const {
    const size_t end = (size_t{at.vertex_base} + object.p_MV.size()) * sizeof(Eigen::Vector3d);
    return places_exactly && object.model_key != 0 && object.p_MV.size() == object.p_WV.size() &&
           end <= buffers[internal::kModelBinding].bytes;
  }
  // Uploads the placements and dispatches the placement kernel; returns the bytes uploaded.
  int64_t PlaceMoved();
  // Runs the placement kernel on probe vertices and poses and compares its positions with
  // WorldVertex's, bit for bit (Create, once).
  bool CheckPlacement();
  // The slots' triangle and node ranges (kSlotsBinding); returns the bytes.
  int64_t UploadSlots(std::span<const SlotLayout> slots);
  // The pair boxes of the objects that pair at all, sorted by low x; returns the bytes.
  int64_t UploadPairBoxes(std::span<const ComputeObject> objects);
  // The boxes of the moved objects' triangles, then their hierarchies level by level, deepest
  // first (the other objects' boxes stay as computed before); returns the bytes uploaded.
  int64_t RefitMoved();
  // Builds and uploads refit_plan for `moved`; returns the bytes uploaded.
  int64_t PlanRefit();
  // The primitive PCS from the traversal's bits, by slot.
  void ReadPcs(ComputeAnswer& answer);
  // The crossing and undecided pairs the traversal wrote (counts from its counters).
  void ReadPairs(uint32_t num_crossing, uint32_t num_undecided, ComputeAnswer& answer);
  // The object pairs the pairs kernel found, sorted.
  void ReadObjectPairs(uint32_t count, ComputeAnswer& answer);

  // A step between Submit and Finish: its query.
  struct Pending {
    ComputeQuery query;
    bool gl_work = false;  // at least two slots have a pair box: the kernels run
    Clock::time_point submit_start, traverse_start, filter_start;  // the timer queries' begins
    GLsync fence = nullptr;  // after the step's last command (SubmitGl), until Collect waits
    int64_t uploaded = 0;
    int64_t vertices_placed = 0;
    double cpu_submit_ms = 0;
  };
  std::optional<Pending> pending;

  // Takes the query and tells whether it has GL work (no GL call).
  void Prepare(const ComputeQuery& query);
  // Uploads, boxes, refit, and the object pairs and traversal's dispatches.
  Result<void> SubmitGl();
  // Binds this collider's buffers, clears the counters and bits, and dispatches the object
  // pairs, their work, the traversal and the filters, with the buffers at `pair_capacity`,
  // `candidate_capacity` and `capacity`.
  void DispatchPairsAndTraversal();
  using Counters = std::array<uint32_t, internal::kNumCounters>;
  // Fails on a stack or count overflow, else grows the buffer that overflowed (the kernels must
  // run again: true) or says that none did (false).
  Result<bool> GrowWhatOverflowed(const Counters& counters);
  // Waits for the kernels (again, with larger buffers, when some overflowed) and reads the
  // answer back.
  Result<ComputeAnswer> Collect();
  // Deletes the programs, buffers and queries. @pre the GL lock is held.
  void DeleteGlObjects();
};

namespace {

// The global index of every node's first child and its triangles' range in the global order,
// as the refit and the traversal read them; the depth of the deepest node.
struct NodeRange {
  uint32_t lo, hi;
};

Result<std::vector<std::vector<uint32_t>>> AppendNodes(const ComputeObject& object,
                                                       uint32_t node_base, uint32_t order_base,
                                                       std::vector<std::array<uint32_t, 4>>& out) {
  const size_t n = object.nodes.size();
  std::vector<NodeRange> range(n);
  std::vector<int> depth(n, 0);
  // Children come after their parent (TriangleBvh builds depth first): one pass down for the
  // depths, one pass up for the ranges.
  int deepest = 0;
  for (size_t i = 0; i < n; ++i) {
    const ComputeNode& node = object.nodes[i];
    if (node.count > 0) continue;
    for (uint32_t c : {node.first, node.first + 1}) {
      if (c <= i || c >= n) {
        return MakeError(ErrorCode::kInternal,
                         "gpu method: a hierarchy node's children are not "
                         "after it");
      }
      depth[c] = depth[i] + 1;
      deepest = std::max(deepest, depth[c]);
    }
  }
  for (size_t k = n; k-- > 0;) {
    const ComputeNode& node = object.nodes[k];
    if (node.count > 0) {
      range[k] = {node.first, node.first + node.count};
    } else {
      const NodeRange left = range[node.first], right = range[node.first + 1];
      if (left.hi != right.lo) {
        return MakeError(ErrorCode::kInternal,
                         "gpu method: a hierarchy node's triangles are not contiguous");
      }
      range[k] = {left.lo, right.hi};
    }
  }
  std::vector<std::vector<uint32_t>> levels(n > 0 ? deepest + 1 : 0);
  for (size_t k = 0; k < n; ++k) {
    const ComputeNode& node = object.nodes[k];
    out.push_back({node.count > 0 ? 0u : node_base + node.first, node.count,
                   order_base + range[k].lo, order_base + range[k].hi});
    levels[depth[k]].push_back(node_base + static_cast<uint32_t>(k));
  }
  return levels;
}

}  // namespace

// Lays the objects out one after another and uploads their triangles and hierarchies when any
// slot's topology changed; returns the bytes uploaded.
Result<int64_t> ComputeCollider::Impl::EnsureLayout(std::span<const ComputeObject> objects) {
  bool same = layout.size() == objects.size();
  for (size_t s = 0; same && s < objects.size(); ++s)
    same = layout[s].topology_key == objects[s].topology_key;
  if (same) return int64_t{0};

  std::vector<SlotLayout> next(objects.size());
  uint64_t vertices = 0, triangles = 0, nodes = 0;
  for (size_t s = 0; s < objects.size(); ++s) {
    const ComputeObject& object = objects[s];
    next[s] = {static_cast<uint32_t>(vertices),
               static_cast<uint32_t>(triangles),
               static_cast<uint32_t>(nodes),
               static_cast<uint32_t>(object.triangles.size()),
               static_cast<uint32_t>(object.nodes.size()),
               object.topology_key,
               0,
               0,
               {}};
    vertices += object.p_WV.size();
    triangles += object.triangles.size();
    nodes += object.nodes.size();
  }
  // Indices are 32-bit in the kernels, and 3 * vertices indexes the positions.
  if (3 * vertices >= std::numeric_limits<uint32_t>::max() ||
      3 * triangles >= std::numeric_limits<uint32_t>::max() ||
      2 * nodes >= std::numeric_limits<uint32_t>::max()) {
    return MakeError(ErrorCode::kUnavailable,
                     "gpu method: the scene is over the kernels' 32-bit indices (" +
                         std::to_string(triangles) + " triangles); 'bvh' answers it");
  }
  std::vector<uint32_t> triangle_vertices;
  triangle_vertices.reserve(3 * triangles);
  std::vector<std::array<uint32_t, 4>> node_data;
  node_data.reserve(nodes);
  std::vector<uint32_t> order;
  order.reserve(triangles);
  for (size_t s = 0; s < objects.size(); ++s) {
    const ComputeObject& object = objects[s];
    SlotLayout& at = next[s];
    for (const TriangleIndices& t : object.triangles) {
      for (int k = 0; k < 3; ++k) triangle_vertices.push_back(at.vertex_base + t[k]);
    }
    auto levels = AppendNodes(object, at.node_base, at.triangle_base, node_data);
    if (!levels) return levels.error();
    const int depth = static_cast<int>(levels->size()) - 1;
    next[s].levels = std::move(*levels);
    if (depth > MaxDepth()) {
      return MakeError(ErrorCode::kUnavailable,
                       "gpu method: an object's hierarchy is " + std::to_string(depth) +
                           " levels deep, over the traversal's " + std::to_string(MaxDepth()) +
                           "; 'bvh' answers this scene");
    }
    for (uint32_t t : object.order) order.push_back(at.triangle_base + t);
  }
  buffer(internal::kPositionsBinding).Reserve(3 * vertices * sizeof(double));
  ReserveModel(objects, vertices);
  // (The triangles, nodes and order are reserved by their uploads below.)
  buffer(internal::kTriBoxesBinding).Reserve(2 * triangles * 4 * sizeof(float));
  buffer(internal::kNodeBoxesBinding).Reserve(2 * nodes * 4 * sizeof(float));
  buffer(internal::kPcsBitsBinding).Reserve((triangles + 31) / 32 * sizeof(uint32_t));
  int64_t uploaded = Upload(internal::kTrianglesBinding, triangle_vertices.data(),
                            triangle_vertices.size() * sizeof(uint32_t));
  uploaded += Upload(internal::kNodesBinding, node_data.data(), node_data.size() * 16);
  uploaded += Upload(internal::kOrderBinding, order.data(), order.size() * sizeof(uint32_t));
  uploaded += UploadSlots(next);
  layout = std::move(next);
  refit_plan = {};
  total_vertices = static_cast<uint32_t>(vertices);
  total_triangles = static_cast<uint32_t>(triangles);
  total_nodes = static_cast<uint32_t>(nodes);
  return uploaded;
}

// Uploads the world vertices of the objects whose world changed since their last upload: one
// upload per run of such objects in consecutive slots (each call costs the driver some
// microseconds; a scene of deforming leaves is then one upload), gathered in `staging`, except
// that an object of kDirectUploadVertices or more goes up on its own, from where it lies: the
// copy cost more than the call saved (scaling-1000000: 8.5 MB of vertices a step).
int64_t ComputeCollider::Impl::UploadVertices(std::span<const ComputeObject> objects) {
  constexpr size_t kDirectUploadVertices = 4096;
  int64_t uploaded = 0;
  moved.clear();
  placements.clear();
  placed_vertices = 0;
  const GLuint positions = buffer(internal::kPositionsBinding).id;
  const auto upload = [&](size_t first_vertex, std::span<const Eigen::Vector3d> vertices) {
    const size_t bytes = vertices.size() * sizeof(Eigen::Vector3d);
    glNamedBufferSubData(positions, static_cast<GLintptr>(first_vertex * sizeof(Eigen::Vector3d)),
                         static_cast<GLsizeiptr>(bytes), vertices.data());
    uploaded += static_cast<int64_t>(bytes);
  };
  std::vector<Eigen::Vector3d>& run = staging;
  size_t run_first = 0;  // first vertex of the run
  const auto flush = [&] {
    if (!run.empty()) upload(run_first, run);
    run.clear();
  };
  for (size_t s = 0; s < objects.size(); ++s) {
    SlotLayout& at = layout[s];
    const std::span<const Eigen::Vector3d> vertices = objects[s].p_WV;
    if (at.world_key == objects[s].world_key || vertices.empty()) {
      flush();
      continue;
    }
    at.world_key = objects[s].world_key;
    moved.push_back(s);
    if (Placeable(at, objects[s])) {
      flush();
      uploaded += AddPlacement(at, objects[s]);
      continue;
    }
    if (vertices.size() >= kDirectUploadVertices) {
      flush();
      upload(at.vertex_base, vertices);
      continue;
    }
    if (run.empty()) run_first = at.vertex_base;
    run.insert(run.end(), vertices.begin(), vertices.end());
  }
  flush();
  return uploaded;
}

void ComputeCollider::Impl::ReserveModel(std::span<const ComputeObject> objects, size_t vertices) {
  const bool posed = std::any_of(objects.begin(), objects.end(),
                                 [](const ComputeObject& object) { return object.model_key != 0; });
  if (places_exactly && posed)
    buffer(internal::kModelBinding).Reserve(3 * vertices * sizeof(double));
}

int64_t ComputeCollider::Impl::AddPlacement(SlotLayout& at, const ComputeObject& object) {
  int64_t uploaded = 0;
  if (at.model_key != object.model_key) {
    const size_t bytes = object.p_MV.size() * sizeof(Eigen::Vector3d);
    glNamedBufferSubData(buffer(internal::kModelBinding).id,
                         static_cast<GLintptr>(at.vertex_base * sizeof(Eigen::Vector3d)),
                         static_cast<GLsizeiptr>(bytes), object.p_MV.data());
    at.model_key = object.model_key;
    uploaded = static_cast<int64_t>(bytes);
  }
  std::array<double, 16> entry{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) entry[4 * i + j] = object.X_WM(i, j);
  }
  entry[12] = at.vertex_base;
  entry[13] = static_cast<double>(object.p_MV.size());
  entry[14] = placed_vertices;
  placements.push_back(entry);
  placed_vertices += static_cast<uint32_t>(object.p_MV.size());
  return uploaded;
}

int64_t ComputeCollider::Impl::PlaceMoved() {
  if (placements.empty()) return 0;
  const int64_t uploaded = Upload(internal::kPlacementsBinding, placements.data(),
                                  placements.size() * sizeof(placements[0]));
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, internal::kPlacementsBinding,
                   buffer(internal::kPlacementsBinding).id);
  glUseProgram(place_program);
  glProgramUniform1ui(place_program, place_count, placed_vertices);
  glProgramUniform1ui(place_program, place_placements, static_cast<GLuint>(placements.size()));
  glDispatchCompute(Groups(placed_vertices), 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  return uploaded;
}

bool ComputeCollider::Impl::CheckPlacement() {
  const internal::PlacementProbe probe = internal::MakePlacementProbe();
  const size_t vertices = probe.p_MV.size();
  buffer(internal::kPositionsBinding).Reserve(3 * vertices * sizeof(double));
  buffer(internal::kModelBinding).Reserve(3 * vertices * sizeof(double));
  placements.clear();
  placed_vertices = 0;
  for (size_t k = 0; k < probe.X_WM.size(); ++k) {
    ComputeObject object;
    object.p_MV =
        std::span(probe.p_MV)
            .subspan(k * internal::PlacementProbe::kVertices, internal::PlacementProbe::kVertices);
    object.X_WM = probe.X_WM[k];
    object.model_key = 1;
    SlotLayout at;
    at.vertex_base = static_cast<uint32_t>(k * internal::PlacementProbe::kVertices);
    AddPlacement(at, object);
  }
  BindBuffers();
  PlaceMoved();
  glUseProgram(0);
  std::vector<Eigen::Vector3d> placed(vertices);
  glGetNamedBufferSubData(buffer(internal::kPositionsBinding).id, 0,
                          static_cast<GLsizeiptr>(vertices * sizeof(Eigen::Vector3d)),
                          placed.data());
  placements.clear();
  placed_vertices = 0;
  for (size_t v = 0; v < vertices; ++v) {
    const Eigen::Vector3d expected =
        WorldVertex(probe.X_WM[v / internal::PlacementProbe::kVertices], probe.p_MV[v]);
    if (std::memcmp(expected.data(), placed[v].data(), sizeof(expected)) != 0) return false;
  }
  return true;
}

int64_t ComputeCollider::Impl::UploadSlots(std::span<const SlotLayout> slots) {
  // Per slot, for the object pairs' work: first triangle, triangles, root node, nodes.
  std::vector<std::array<uint32_t, 4>> table;
  table.reserve(slots.size());
  for (const SlotLayout& at : slots)
    table.push_back({at.triangle_base, at.triangles, at.node_base, at.nodes});
  return Upload(internal::kSlotsBinding, table.data(), table.size() * sizeof(table[0]));
}

int64_t ComputeCollider::Impl::UploadPairBoxes(std::span<const ComputeObject> objects) {
  // The boxes of the objects that pair at all, by low x: the kernel sweeps them in this order.
  std::vector<std::array<double, 8>> boxes;
  for (size_t s = 0; s < objects.size(); ++s) {
    if (!PairsAtAll(objects[s])) continue;
    const Eigen::Vector3d& lo = objects[s].pair_box.min();
    const Eigen::Vector3d& hi = objects[s].pair_box.max();
    boxes.push_back({lo.x(), lo.y(), lo.z(), static_cast<double>(s), hi.x(), hi.y(), hi.z(), 0.0});
  }
  std::sort(boxes.begin(), boxes.end(), [](const auto& a, const auto& b) { return a[0] < b[0]; });
  num_pair_boxes = boxes.size();
  return Upload(internal::kPairBoxesBinding, boxes.data(), boxes.size() * sizeof(boxes[0]));
}

int64_t ComputeCollider::Impl::PlanRefit() {
  RefitPlan plan;
  plan.moved = moved;
  std::vector<std::array<uint32_t, 2>> ranges;  // (first triangle, triangles before)
  size_t levels = 0;
  for (size_t s : moved) {
    ranges.push_back({layout[s].triangle_base, plan.triangles});
    plan.triangles += layout[s].triangles;
    levels = std::max(levels, layout[s].levels.size());
  }
  plan.ranges = static_cast<uint32_t>(ranges.size());
  // The nodes, deepest level first: level d is list[begin[d], end[d]).
  std::vector<uint32_t> list;
  plan.begin.resize(levels);
  plan.end.resize(levels);
  for (size_t d = levels; d-- > 0;) {
    plan.begin[d] = list.size();
    for (size_t s : moved) {
      if (d < layout[s].levels.size())
        list.insert(list.end(), layout[s].levels[d].begin(), layout[s].levels[d].end());
    }
    plan.end[d] = list.size();
  }
  Buffer& range_buffer = buffer(internal::kRangesBinding);
  Buffer& list_buffer = buffer(internal::kRefitListBinding);
  range_buffer.Reserve(ranges.size() * 8);
  list_buffer.Reserve(list.size() * 4);
  glNamedBufferSubData(range_buffer.id, 0, static_cast<GLsizeiptr>(ranges.size() * 8),
                       ranges.data());
  glNamedBufferSubData(list_buffer.id, 0, static_cast<GLsizeiptr>(list.size() * 4), list.data());
  refit_plan = std::move(plan);
  return static_cast<int64_t>(ranges.size() * 8 + list.size() * 4);
}

int64_t ComputeCollider::Impl::RefitMoved() {
  if (moved.empty()) return 0;
  const int64_t uploaded = refit_plan.moved == moved ? 0 : PlanRefit();
  const RefitPlan& plan = refit_plan;
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, internal::kRangesBinding,
                   buffer(internal::kRangesBinding).id);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, internal::kRefitListBinding,
                   buffer(internal::kRefitListBinding).id);
  glUseProgram(boxes_program);
  glProgramUniform1ui(boxes_program, boxes_count, plan.triangles);
  glProgramUniform1ui(boxes_program, boxes_ranges, plan.ranges);
  glDispatchCompute(Groups(plan.triangles), 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  glUseProgram(refit_program);
  for (size_t d = plan.begin.size(); d-- > 0;) {
    if (plan.end[d] == plan.begin[d]) continue;
    glProgramUniform1ui(refit_program, refit_first, static_cast<GLuint>(plan.begin[d]));
    glProgramUniform1ui(refit_program, refit_count,
                        static_cast<GLuint>(plan.end[d] - plan.begin[d]));
    glDispatchCompute(Groups(plan.end[d] - plan.begin[d]), 1, 1);
    glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  }
  return uploaded;
}

void ComputeCollider::Impl::ReadPcs(ComputeAnswer& answer) {
  const uint32_t* bits = copies.At<uint32_t>(BitsOffset());
  answer.pcs.resize(layout.size());
  for (size_t s = 0; s < layout.size(); ++s) {
    // The slot's triangles are bits [base, end) of the words: visit the set ones only.
    const uint32_t base = layout[s].triangle_base, end = base + layout[s].triangles;
    if (base == end) continue;
    const uint32_t first = base >> 5, last = (end - 1) >> 5;
    for (uint32_t w = first; w <= last; ++w) {
      uint32_t word = bits[w];
      if (w == first) word &= ~0u << (base & 31);                      // before the slot
      if (w == last && (end & 31) != 0) word &= ~(~0u << (end & 31));  // after it
      for (; word != 0; word &= word - 1)
        answer.pcs[s].push_back(w * 32 + static_cast<uint32_t>(std::countr_zero(word)) - base);
    }
  }
}

void ComputeCollider::Impl::ReadPairs(uint32_t num_crossing, uint32_t num_undecided,
                                      ComputeAnswer& answer) {
  // A crossing entry is a SlotContact as the kernel writes it: copied straight into the answer.
  static_assert(sizeof(SlotContact) == 16 && std::is_standard_layout_v<SlotContact> &&
                offsetof(SlotContact, triangle_a) == 4 && offsetof(SlotContact, object_b) == 8 &&
                offsetof(SlotContact, triangle_b) == 12);
  const SlotContact* crossing = buffer(internal::kCrossingBinding).At<SlotContact>(0);
  answer.crossing.assign(crossing, crossing + num_crossing);
  // An undecided entry carries the proven-apart flag in its partner's slot.
  const auto* entries = buffer(internal::kUndecidedBinding).At<std::array<uint32_t, 4>>(0);
  answer.undecided.reserve(num_undecided);
  answer.proven_apart.reserve(num_undecided);
  for (uint32_t i = 0; i < num_undecided; ++i) {
    const auto& e = entries[i];
    answer.undecided.push_back({SlotAt(e[0]), e[1], SlotAt(e[2] & 0x7fffffffu), e[3]});
    answer.proven_apart.push_back((e[2] & 0x80000000u) != 0 ? 1 : 0);
  }
}

void ComputeCollider::Impl::ReadObjectPairs(uint32_t count, ComputeAnswer& answer) {
  const auto* pairs = copies.At<std::array<uint32_t, 2>>(kPairsOffset);
  answer.object_pairs.reserve(count);
  for (uint32_t i = 0; i < count; ++i)
    answer.object_pairs.push_back({SlotAt(pairs[i][0]), SlotAt(pairs[i][1])});
  std::sort(answer.object_pairs.begin(), answer.object_pairs.end());
}

void ComputeCollider::Impl::DispatchPairsAndTraversal() {
  const ComputeQuery& query = pending->query;
  buffer(internal::kObjectPairsBinding).Reserve(pair_capacity * 8);
  buffer(internal::kWorkBinding).Reserve(pair_capacity * 32);
  buffer(internal::kWorkStartBinding).Reserve((pair_capacity + 1) * sizeof(uint32_t));
  buffer(internal::kDispatchBinding).Reserve(internal::kNumDispatchWords * sizeof(uint32_t));
  buffer(internal::kCandidatesBinding).Reserve(candidate_capacity * 16);
  buffer(internal::kCrossingBinding).Reserve(capacity * 16);
  buffer(internal::kUndecidedBinding).Reserve(capacity * 16);
  const uint32_t zero = 0;
  glClearNamedBufferData(buffer(internal::kCountersBinding).id, GL_R32UI, GL_RED_INTEGER,
                         GL_UNSIGNED_INT, &zero);
  glClearNamedBufferData(buffer(internal::kPcsBitsBinding).id, GL_R32UI, GL_RED_INTEGER,
                         GL_UNSIGNED_INT, &zero);
  // Every binding again: another collider of the context may have bound its own since.
  BindBuffers();
  pending->traverse_start = Clock::now();
  glBeginQuery(GL_TIME_ELAPSED, traverse_query);
  // The object pairs: a box per invocation sweeps the boxes after it.
  glUseProgram(pairs_program);
  glProgramUniform1ui(pairs_program, pairs_boxes, static_cast<GLuint>(num_pair_boxes));
  glProgramUniform1ui(pairs_program, pairs_capacity, static_cast<GLuint>(pair_capacity));
  glDispatchCompute(Groups(num_pair_boxes), 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  // Their work and the traversal's dispatch, which the traversal then reads as commands.
  glUseProgram(work_program);
  glProgramUniform1ui(work_program, work_capacity, static_cast<GLuint>(pair_capacity));
  glDispatchCompute(1, 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, buffer(internal::kDispatchBinding).id);
  // The traversal appends the triangle pairs whose boxes meet...
  glUseProgram(traverse_program);
  glProgramUniform1f(traverse_program, traverse_slack, FloatAtLeast(query.slack));
  glProgramUniform1ui(traverse_program, traverse_capacity, static_cast<GLuint>(candidate_capacity));
  glDispatchComputeIndirect(internal::kGroupsX * sizeof(GLuint));
  glEndQuery(GL_TIME_ELAPSED);
  pending->filter_start = Clock::now();
  glBeginQuery(GL_TIME_ELAPSED, filter_query);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT);
  glUseProgram(filter_dispatch_program);
  glProgramUniform1ui(filter_dispatch_program, filter_dispatch_capacity,
                      static_cast<GLuint>(candidate_capacity));
  glDispatchCompute(1, 1, 1);
  glMemoryBarrier(GL_SHADER_STORAGE_BARRIER_BIT | GL_COMMAND_BARRIER_BIT);
  // ...and the filters classify them, one per invocation.
  const FilterKernel& kernel = filter[query.distance ? 1 : 0];
  glUseProgram(kernel.program);
  glProgramUniform1ui(kernel.program, kernel.capacity, static_cast<GLuint>(capacity));
  if (query.distance) glProgramUniform1d(kernel.program, kernel.max_distance, query.max_distance);
  glDispatchComputeIndirect(internal::kFilterGroupsX * sizeof(GLuint));
  glBindBuffer(GL_DISPATCH_INDIRECT_BUFFER, 0);
  glEndQuery(GL_TIME_ELAPSED);
  glUseProgram(0);
  // What the CPU reads, into the read-back buffers: the filters wrote their pairs there, the
  // rest is copied after them.
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_CLIENT_MAPPED_BUFFER_BARRIER_BIT);
  const size_t bits_bytes = (total_triangles + 31) / 32 * sizeof(uint32_t);
  copies.Reserve(BitsOffset() + bits_bytes);
  const auto copy = [&](internal::ComputeBinding from, size_t offset, size_t bytes) {
    if (bytes > 0) {
      glCopyNamedBufferSubData(buffer(from).id, copies.id, 0, static_cast<GLintptr>(offset),
                               static_cast<GLsizeiptr>(bytes));
    }
  };
  copy(internal::kCountersBinding, 0, internal::kNumCounters * sizeof(uint32_t));
  copy(internal::kObjectPairsBinding, kPairsOffset, pair_capacity * 8);
  copy(internal::kPcsBitsBinding, BitsOffset(), bits_bytes);
}

Result<bool> ComputeCollider::Impl::GrowWhatOverflowed(const Counters& counters) {
  if (counters[internal::kStackOverflow] != 0) {
    return MakeError(ErrorCode::kInternal,
                     "gpu method: a traversal ran out of stack (a hierarchy deeper than checked)");
  }
  // Too many object pairs: their work and the traversal saw only the first pair_capacity.
  const size_t object_pairs = counters[internal::kObjectPairCount];
  if (object_pairs > pair_capacity) {
    if (object_pairs > kMostPairCapacity) {
      return MakeError(ErrorCode::kLimitExceeded, "gpu method: " + std::to_string(object_pairs) +
                                                      " object pairs, over its limit " +
                                                      std::to_string(kMostPairCapacity) +
                                                      "; 'bvh' answers this scene");
    }
    pair_capacity = GrownCapacity(object_pairs, kMostPairCapacity);
    return true;
  }
  if (counters[internal::kWorkOverflow] != 0) {
    return MakeError(ErrorCode::kUnavailable,
                     "gpu method: over 2^32 triangles to descend in one step; 'bvh' answers "
                     "this scene");
  }
  // Too many triangle pairs whose boxes meet: the filters saw only the first
  // candidate_capacity (the outputs hold at most as many).
  const size_t box_pairs = counters[internal::kBoxPairs];
  if (box_pairs > candidate_capacity) {
    if (box_pairs > kMostCapacity) {
      return MakeError(ErrorCode::kLimitExceeded,
                       "gpu method: " + std::to_string(box_pairs) +
                           " triangle pairs whose boxes meet, over its limit " +
                           std::to_string(kMostCapacity) + "; 'bvh' answers this scene");
    }
    candidate_capacity = GrownCapacity(box_pairs, kMostCapacity);
    return true;
  }
  const size_t most =
      std::max(counters[internal::kCrossingCount], counters[internal::kUndecidedCount]);
  if (most <= capacity) return false;
  capacity = GrownCapacity(most, candidate_capacity);
  return true;
}

Result<ComputeAnswer> ComputeCollider::Impl::Collect() {
  ComputeAnswer answer;
  answer.cpu_submit_ms = pending->cpu_submit_ms;
  answer.bytes_uploaded = pending->uploaded;
  answer.vertices_placed = pending->vertices_placed;
  Counters counters{};
  GLsync fence = std::exchange(pending->fence, nullptr);
  for (;;) {
    const auto wait_start = Clock::now();
    WaitAndDelete(fence);
    answer.cpu_wait_ms += MsSince(wait_start);
    if (auto ok = CheckGl("gpu method: the traversal"); !ok) return ok.error();
    if (copies.mapped == nullptr || buffer(internal::kCrossingBinding).mapped == nullptr ||
        buffer(internal::kUndecidedBinding).mapped == nullptr) {
      return MakeError(ErrorCode::kInternal,
                       "gpu method: the driver did not map the read-back buffers");
    }
    std::memcpy(counters.data(), copies.mapped, sizeof(counters));
    auto grew = GrowWhatOverflowed(counters);
    if (!grew) return grew.error();
    if (!*grew) break;
    ++answer.runs;
    DispatchPairsAndTraversal();
    fence = FenceAndFlush();
  }
  const auto read_start = Clock::now();
  ReadObjectPairs(counters[internal::kObjectPairCount], answer);
  ReadPairs(counters[internal::kCrossingCount], counters[internal::kUndecidedCount], answer);
  ReadPcs(answer);
  const GLuint64 refit_ns = internal::ElapsedNsOrZero(refit_query, pending->submit_start);
  const GLuint64 traverse_ns = internal::ElapsedNsOrZero(traverse_query, pending->traverse_start);
  const GLuint64 filter_ns = internal::ElapsedNsOrZero(filter_query, pending->filter_start);
  answer.gpu_refit_ms = 1e-6 * static_cast<double>(refit_ns);
  answer.gpu_traverse_ms = 1e-6 * static_cast<double>(traverse_ns);
  answer.gpu_filter_ms = 1e-6 * static_cast<double>(filter_ns);
  answer.cpu_read_ms = MsSince(read_start);
  answer.cpu_wait_ms += answer.cpu_read_ms;
  if (auto ok = CheckGl("gpu method: reading the pairs back"); !ok) return ok.error();
  answer.box_pairs = counters[internal::kBoxPairs];
  answer.float_decided = counters[internal::kFloatDecided];
  answer.double_decided = counters[internal::kDoubleDecided];
  answer.distance_culled = counters[internal::kDistanceCulled];
  return answer;
}

ComputeCollider::ComputeCollider(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

// Names not made yet are 0, which GL's deletes ignore: this also cleans up after a Create that
// failed halfway.
void ComputeCollider::Impl::DeleteGlObjects() {
  if (pending && pending->fence != nullptr) glDeleteSync(pending->fence);
  for (Buffer& b : buffers) glDeleteBuffers(1, &b.id);
  glDeleteBuffers(1, &copies.id);
  glDeleteQueries(1, &refit_query);
  glDeleteQueries(1, &traverse_query);
  glDeleteQueries(1, &filter_query);
  for (GLuint program :
       {place_program, boxes_program, refit_program, pairs_program, work_program, traverse_program,
        filter_dispatch_program, filter[0].program, filter[1].program})
    glDeleteProgram(program);
}

ComputeCollider::~ComputeCollider() {
  const auto lock = LockGl();
  impl_->DeleteGlObjects();
}

bool ComputeCollider::PlacesOnGpu() const { return impl_->places_exactly; }

int ComputeCollider::MaxDepth() { return internal::kTraversalStack - 2; }

Result<std::unique_ptr<ComputeCollider>> ComputeCollider::Create() {
  const auto lock = LockGl();
  auto impl = std::make_unique<Impl>();
  // A kernel that does not compile leaves the programs made before it, and a GL error the
  // buffers: deleted on the way out, under the lock.
  struct DeleteUnlessKept {
    Impl* impl;
    ~DeleteUnlessKept() {
      if (impl != nullptr) impl->DeleteGlObjects();
    }
  } made{impl.get()};
  const std::tuple<GLuint*, std::string, const char*> kernels[] = {
      {&impl->place_program, internal::PlaceSource(), "placement"},
      {&impl->boxes_program, internal::TriangleBoxesSource(), "triangle boxes"},
      {&impl->refit_program, internal::RefitSource(), "refit"},
      {&impl->pairs_program, internal::ObjectPairsSource(), "object pairs"},
      {&impl->work_program, internal::PairWorkSource(), "object pairs' work"},
      {&impl->traverse_program, internal::TraverseSource(), "traversal"},
      {&impl->filter_dispatch_program, internal::FilterDispatchSource(), "filters' dispatch"},
      {&impl->filter[0].program, internal::FilterSource(false), "filters"},
      {&impl->filter[1].program, internal::FilterSource(true), "distance filters"}};
  for (const auto& [program, source, what] : kernels) {
    auto compiled = CompileCompute(source, what);
    if (!compiled) return compiled.error();
    *program = *compiled;
  }
  for (Impl::FilterKernel& kernel : impl->filter) {
    kernel.capacity = glGetUniformLocation(kernel.program, "u_capacity");
    kernel.max_distance = glGetUniformLocation(kernel.program, "u_max_distance");
  }
  impl->traverse_slack = glGetUniformLocation(impl->traverse_program, "u_slack");
  impl->traverse_capacity = glGetUniformLocation(impl->traverse_program, "u_candidate_capacity");
  impl->filter_dispatch_capacity =
      glGetUniformLocation(impl->filter_dispatch_program, "u_candidate_capacity");
  impl->place_count = glGetUniformLocation(impl->place_program, "u_count");
  impl->place_placements = glGetUniformLocation(impl->place_program, "u_placements");
  impl->place_tiny = glGetUniformLocation(impl->place_program, "u_tiny");
  glProgramUniform1d(impl->place_program, impl->place_tiny, kTinyWorldCoordinate);
  impl->boxes_count = glGetUniformLocation(impl->boxes_program, "u_count");
  impl->boxes_ranges = glGetUniformLocation(impl->boxes_program, "u_ranges");
  impl->refit_count = glGetUniformLocation(impl->refit_program, "u_count");
  impl->refit_first = glGetUniformLocation(impl->refit_program, "u_first");
  impl->pairs_boxes = glGetUniformLocation(impl->pairs_program, "u_boxes");
  impl->pairs_capacity = glGetUniformLocation(impl->pairs_program, "u_pair_capacity");
  impl->work_capacity = glGetUniformLocation(impl->work_program, "u_pair_capacity");
  for (Buffer& b : impl->buffers) glCreateBuffers(1, &b.id);
  impl->buffer(internal::kCrossingBinding).read_back = true;
  impl->buffer(internal::kUndecidedBinding).read_back = true;
  glCreateQueries(GL_TIME_ELAPSED, 1, &impl->refit_query);
  glCreateQueries(GL_TIME_ELAPSED, 1, &impl->traverse_query);
  glCreateQueries(GL_TIME_ELAPSED, 1, &impl->filter_query);
  impl->buffer(internal::kCountersBinding).Reserve(internal::kNumCounters * sizeof(uint32_t));
  if (auto ok = CheckGl("gpu method: making its buffers"); !ok) return ok.error();
  impl->places_exactly = impl->CheckPlacement();
  if (auto ok = CheckGl("gpu method: checking its placement"); !ok) return ok.error();
  made.impl = nullptr;
  return std::unique_ptr<ComputeCollider>(new ComputeCollider(std::move(impl)));
}

void ComputeCollider::Impl::Prepare(const ComputeQuery& query) {
  Pending next;
  next.query = query;
  // Fewer than two objects with a pair box have no pair: no GL work, not even the lock.
  size_t pairing = 0;
  for (const ComputeObject& object : query.objects) pairing += PairsAtAll(object) ? 1 : 0;
  next.gl_work = pairing >= 2;
  pending = std::move(next);
}

Result<void> ComputeCollider::Impl::SubmitGl() {
  Pending& step = *pending;
  step.submit_start = Clock::now();
  glBeginQuery(GL_TIME_ELAPSED, refit_query);
  auto laid_out = EnsureLayout(step.query.objects);
  if (!laid_out) {
    glEndQuery(GL_TIME_ELAPSED);
    return laid_out.error();
  }
  int64_t uploaded = *laid_out + UploadVertices(step.query.objects);
  uploaded += UploadPairBoxes(step.query.objects);
  BindBuffers();
  uploaded += PlaceMoved();
  step.vertices_placed = placed_vertices;
  uploaded += RefitMoved();
  glEndQuery(GL_TIME_ELAPSED);
  glUseProgram(0);
  if (auto ok = CheckGl("gpu method: boxes and refit"); !ok) return ok.error();
  DispatchPairsAndTraversal();
  step.fence = FenceAndFlush();
  step.uploaded = uploaded;
  step.cpu_submit_ms = MsSince(step.submit_start);
  return {};
}

Result<void> ComputeCollider::Submit(const ComputeQuery& query) {
  impl_->Prepare(query);
  if (!impl_->pending->gl_work) return {};
  if (auto ok = impl_->SubmitGl(); !ok) {
    impl_->pending.reset();
    return ok;
  }
  return {};
}

bool ComputeCollider::Ready() const {
  const std::optional<Impl::Pending>& step = impl_->pending;
  if (!step || !step->gl_work || step->fence == nullptr) return true;
  return glClientWaitSync(step->fence, 0, 0) != GL_TIMEOUT_EXPIRED;
}

Result<ComputeAnswer> ComputeCollider::Finish() {
  if (!impl_->pending)
    return MakeError(ErrorCode::kInternal, "gpu method: Finish without a step submitted");
  Result<ComputeAnswer> answer = impl_->pending->gl_work ? impl_->Collect() : ComputeAnswer{};
  impl_->pending.reset();
  return answer;
}

Result<ComputeAnswer> ComputeCollider::Run(const ComputeQuery& query) {
  impl_->Prepare(query);
  if (!impl_->pending->gl_work) {  // no GL work: not even the lock
    impl_->pending.reset();
    return ComputeAnswer{};
  }
  // FAR_COMPUTE_GL_LOCK=off: this step's GL work runs without far::LockGl, beside other
  // sessions' (an experiment for drivers that need no lock between contexts: docs/daemon.md).
  static const bool unlocked = [] {
    const char* value = std::getenv("FAR_COMPUTE_GL_LOCK");
    return value != nullptr && std::string(value) == "off";
  }();
  const auto submit_and_finish = [&]() -> Result<ComputeAnswer> {
    if (auto ok = impl_->SubmitGl(); !ok) {
      impl_->pending.reset();
      return ok.error();
    }
    return Finish();
  };
  if (unlocked) return submit_and_finish();
  const auto lock = LockGl();
  return submit_and_finish();
}

}  // namespace far
