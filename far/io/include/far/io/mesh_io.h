#pragma once

// Strict readers and writers for triangle mesh files: Wavefront OBJ, PLY (ascii, binary little-
// and big-endian) and STL (ascii and binary).
//
// Every reader either returns the whole mesh or an error; never a partial mesh. Triangle index t
// is the t-th triangle the file produces: polygons are fan-triangulated in file order, a polygon
// (v0, v1, ..., vn-1) giving triangles (v0, v1, v2), (v0, v2, v3), ..., (v0, vn-2, vn-1).
// Vertex index i is the i-th vertex of the file (OBJ `v` lines, PLY `vertex` elements); STL has
// no shared vertices, so facet t gives vertices 3t, 3t+1, 3t+2 (never welded).
//
// Errors:
//  - kIoError: the file cannot be opened or read (message names the path).
//  - kParseError: the file is malformed; the message starts with the file name and the line
//    ("leaf.obj:12: face index 9 out of range (8 vertices)") or byte offset ("part.stl: byte 84:
//    truncated: ..."), then says what is wrong. Non-finite coordinates, out-of-range indices and
//    files with no triangles ("no triangles") are errors.
//  - kLimitExceeded: more than 2^31-1 vertices or triangles.
// The format is documented in docs/scene-format.md ("Mesh files").
//
// Thread safety: all functions are reentrant; they share no state.

#include <filesystem>
#include <string_view>

#include "far/base/result.h"
#include "far/model/mesh.h"

namespace far {

/// Reads the mesh file at `path`, choosing the format by its extension (.obj, .ply or .stl,
/// case-insensitive). Returns kInvalidArgument for any other extension; see above for the rest.
Result<Mesh> ReadMesh(const std::filesystem::path& path);

/// Reads a Wavefront OBJ file. Statements: `v x y z [w]` (also `v x y z r g b`; w and colors
/// are checked to be numbers and ignored); `f` with `i`, `i/t`, `i//n` or `i/t/n` references
/// (1-based; negative means relative to the last vertex so far; a face may only reference
/// vertices, texture coordinates and normals defined above it). vt, vn, vp, l, p, g, o, s,
/// mg, usemtl, mtllib and the display/render attributes are ignored; free-form geometry
/// (cstype, curv, surf, ...) and unknown statements are errors, since skipping them would
/// lose geometry silently.
Result<Mesh> ReadObj(const std::filesystem::path& path);
/// Parses OBJ text held in memory; `name_for_errors` starts every error message.
Result<Mesh> ReadObj(std::string_view bytes, std::string_view name_for_errors);

/// Reads a PLY file (format ascii, binary_little_endian or binary_big_endian, version 1.0).
/// Element `vertex` must have scalar properties x, y, z of any numeric type; element `face`
/// must have one list property named vertex_indices or vertex_index with integer count and index
/// types. Other properties and elements are skipped by their declared types. Element counts are
/// checked against the file size before anything is allocated.
Result<Mesh> ReadPly(const std::filesystem::path& path);
/// Parses PLY bytes held in memory; `name_for_errors` starts every error message.
Result<Mesh> ReadPly(std::string_view bytes, std::string_view name_for_errors);

/// Reads an STL file. The file is binary when its size is exactly 84 + 50 n, n being the
/// triangle count in bytes 80..83, even when it starts with "solid" (the known STL ambiguity);
/// otherwise a file starting with "solid" is parsed as ascii STL, and anything else is reported
/// as a binary STL of the wrong size. Facet normals are ignored.
Result<Mesh> ReadStl(const std::filesystem::path& path);
/// Parses STL bytes held in memory; `name_for_errors` starts every error message.
Result<Mesh> ReadStl(std::string_view bytes, std::string_view name_for_errors);

/// Writes `mesh` as OBJ text (`v` with shortest round-trip decimals, then 1-based `f`), so
/// ReadObj gives back exactly the same mesh. Returns kInvalidArgument when ValidateMesh fails,
/// kIoError when the file cannot be written.
Result<void> WriteObj(const Mesh& mesh, const std::filesystem::path& path);

/// Writes `mesh` as binary little-endian PLY with double x, y, z and uint8-counted uint32
/// vertex_indices, so ReadPly gives back exactly the same mesh. Errors as WriteObj.
Result<void> WritePly(const Mesh& mesh, const std::filesystem::path& path);

/// Writes `mesh` as binary STL: positions rounded to float32, normals computed, three vertices
/// per facet (ReadStl gives back 3 * num_triangles() vertices). Errors as WriteObj; also
/// kInvalidArgument when a coordinate does not fit in a float.
Result<void> WriteStl(const Mesh& mesh, const std::filesystem::path& path);

/// Writes `mesh` in the format named by the extension of `path` (.obj, .ply or .stl,
/// case-insensitive); kInvalidArgument for any other extension. Errors as WriteObj.
Result<void> WriteMesh(const Mesh& mesh, const std::filesystem::path& path);

}  // namespace far
