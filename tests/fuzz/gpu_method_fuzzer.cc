// Fuzz target gpu_method: the gpu method (compute shaders: boxes rounded outward to float,
// hierarchies refit and descended on the GPU, triangle pairs decided by float and fp64 filters
// with proven bounds, the rest by the CPU's exact predicates) on the process's GL context
// (llvmpipe in CI; a GPU through the EGL device platform where there is one), held to the
// brute-force reference as gl_methods holds FAR: a far::Pipeline stepped through a few frames of
// a small scene the bytes describe, and at every step gpu must answer exactly what `exact`
// answers, for touching, coplanar and degenerate triangles on the grid, at tiny scales, and with
// the whole scene up to 1e7 from the origin, where the float filter can certify nothing and the
// fp64 one must.
//
// Input, front to back (past the end every byte reads as 0):
//   uint8 shift: bits 0-2 the shift s of every translation (GridShift: 0 to 1e7 along
//         (1, -0.5, 0.25))
//   then a scene and its steps, as cpu_methods_fuzzer.cc lays them out.
//
// Oracles besides the sanitizers: every update is accepted; every step succeeds; gpu's contacts
// and distance pairs are exact's, pair for pair.

#include <cstdint>
#include <memory>

#include "fuzz_grid.h"
#include "fuzz_input.h"
#include "fuzz_scene.h"

#include "far/gpu/gl_context.h"
#include "far/pipeline/pipeline.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far;
  using namespace far::fuzz;
  // One context for the process, never destroyed (gl_methods_fuzzer.cc says why).
  [[maybe_unused]] static GlContext* const context = [] {
    auto made = GlContext::Create();
    FAR_FUZZ_CHECK(made.ok());
    return made->release();
  }();
  FuzzInput in(data, size);
  const int shift = in.Take<uint8_t>() & 7;
  SceneSpec spec = ReadSceneSpec(in);
  spec.grid.shift = GridShift(shift);
  StepRequest request;
  request.method = Method::kGpu;
  request.distance = spec.distance;
  request.output = spec.distance ? Output::kDistancePairs : Output::kContacts;
  StepOnGlAgainstExact(in, spec, request);
  return 0;
}
