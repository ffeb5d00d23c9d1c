// Fuzz target gl_methods: FAR's GPU culling (methods far and far-exact-offset) on the process's
// GL context (llvmpipe in CI; a GPU through the EGL device platform where there is one), held to
// the brute-force reference as cpu_methods holds the CPU methods: a far::Pipeline stepped through
// a few frames of a small scene the bytes describe, and at every step the GL method must answer
// exactly what `exact` answers. The GPU path culls in float from fattened primitives; what it
// must never do is prune a triangle of a contact or of a pair within D: at any resolution,
// depth format, mechanism and sub-object size, for touching, coplanar and degenerate triangles
// on the grid, at tiny scales, and with the whole scene up to 1e7 from the origin.
//
// Input, front to back (past the end every byte reads as 0):
//   uint8 culling: bit 0 far-exact-offset (else far), bit 1 occlusion queries (else the ID
//         buffer), bits 2-3 the depth format (n % 3: depth16, depth24, depth32f), bits 4-6 the
//         shift s of every translation (GridShift: 0 to 1e7 along (1, -0.5, 0.25))
//   uint8 resolution: 8 << (n % 7) (8 to 512 pixels)
//   uint8 sub-object size: 1 + n % 4
//   then a scene and its steps, as cpu_methods_fuzzer.cc lays them out.
//
// Oracles besides the sanitizers: every update is accepted; every step succeeds; the GL method's
// contacts and distance pairs are exact's, pair for pair.

#include <cstdint>
#include <memory>

#include "fuzz_grid.h"
#include "fuzz_input.h"
#include "fuzz_scene.h"

#include "far/gpu/gl_context.h"
#include "far/pipeline/pipeline.h"

namespace far::fuzz {
namespace {

// The step request the culling byte, the resolution byte and the sub-object byte describe.
StepRequest ReadCulling(FuzzInput& in, int& shift) {
  const uint8_t culling = in.Take<uint8_t>();
  StepRequest request;
  request.method = culling & 1 ? Method::kFarExactOffset : Method::kFar;
  request.mechanism = culling & 2 ? QueryMechanism::kOcclusionQuery : QueryMechanism::kIdBuffer;
  constexpr DepthFormat kFormats[] = {DepthFormat::kDepth16, DepthFormat::kDepth24,
                                      DepthFormat::kDepth32F};
  request.depth_format = kFormats[((culling >> 2) & 3) % 3];
  shift = (culling >> 4) & 7;
  request.resolution = 8 << (in.Take<uint8_t>() % 7);
  request.subobject_size = 1 + in.Take<uint8_t>() % 4;
  return request;
}

}  // namespace
}  // namespace far::fuzz

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace far;
  using namespace far::fuzz;
  // One context for the process (making one takes a large part of a second on llvmpipe); each
  // input gets a pipeline of its own on it, so that no state carries from one input to the next.
  // It is never destroyed: terminating EGL at exit unloads the driver, whose few blocks then
  // read as leaks from an unknown module.
  [[maybe_unused]] static GlContext* const context = [] {
    auto made = GlContext::Create();
    FAR_FUZZ_CHECK(made.ok());
    return made->release();
  }();
  FuzzInput in(data, size);
  int shift = 0;
  StepRequest request = ReadCulling(in, shift);
  SceneSpec spec = ReadSceneSpec(in);
  spec.grid.shift = GridShift(shift);
  request.distance = spec.distance;
  request.output = spec.distance ? Output::kDistancePairs : Output::kContacts;
  StepOnGlAgainstExact(in, spec, request);
  return 0;
}
