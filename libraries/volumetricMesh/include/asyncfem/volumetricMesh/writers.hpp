// SPDX-License-Identifier: BSD-3-Clause
#pragma once

#include <Eigen/Core>
#include <asyncfem/volumetricMesh/tetMesh.hpp>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace asyncfem {

/// Writes the mesh as Vega .veg: vertices, TET elements (CUBIC for a hexahedral mesh), one *MATERIAL per material,
/// one *SET per element set, one *VERTEXSET per vertex set, and one *REGION line per
/// material naming a set with exactly that material's elements (an existing set, or an
/// added `__material_<name>` set that readVeg does not keep), so that
/// readVeg(writeVeg(m)) reproduces m exactly: every double is printed in the shortest form
/// that reads back to the same bits (at most 17 significant digits). This holds for
/// meshes whose elements are positively oriented and non-degenerate (readers reorient
/// or reject the others). Names must be single tokens (no spaces, commas or '#'), else
/// ValidationError. Writes to PATH.tmp and renames it, so a failure never leaves a
/// half-written file; asyncfem::Error if the file cannot be written.
void writeVeg(const std::filesystem::path& path, const TetMesh& mesh);

/// A named per-vertex (or per-element) array to add to a .vtu file.
struct VtuArray {
  std::string name;
  int components = 1;          ///< 1 (scalar) or 3 (vector)
  std::vector<double> values;  ///< components * count values, interleaved
};

/// How writeVtu stores its arrays.
enum class VtuEncoding {
  /// VTK XML appended data, raw bytes (`format="appended"`, `encoding="raw"`,
  /// `header_type="UInt64"`): every array is one UInt64 byte count followed by its values
  /// in the machine's byte order (stated in `byte_order`). About 3x smaller than ASCII
  /// and exact.
  binary,
  /// Every value as text inside its DataArray (doubles in the shortest form that reads
  /// back to the same bits), for reading by eye or by tools without a VTK reader.
  ascii,
};

/// Writes an unstructured-grid VTK XML file (version 1.0) that ParaView opens: points at
/// the **rest positions**, the point array "displacement" (3 components) when
/// displacement is given (empty: the rest shape only; else 3n stacked x y z per vertex),
/// tetrahedra (VTK type 10) or hexahedra (VTK type 12, the mesh's vertex order), a per-cell Int32 "material" array
/// (material index), and the given point and cell arrays (ValidationError if a size or component count is wrong). The
/// deformed shape is rest + displacement: in ParaView apply Warp By Vector with "displacement" (scale 1). Written to
/// PATH.tmp and renamed over PATH.
void writeVtu(const std::filesystem::path& path, const TetMesh& mesh, const Eigen::VectorXd& displacement = {},
              const std::vector<VtuArray>& pointArrays = {}, const std::vector<VtuArray>& cellArrays = {},
              VtuEncoding encoding = VtuEncoding::binary);

/// One data set of a .pvd collection: a file (relative to the .pvd's folder, or
/// absolute) shown at a time.
struct PvdEntry {
  double time = 0.0;
  std::filesystem::path file;
};

/// Writes a ParaView collection (.pvd, VTK XML type "Collection") listing the files with
/// their times, in the given order, so that ParaView opens a frame series with its
/// simulated times. Written to PATH.tmp and renamed over PATH, so rewriting it after
/// every frame always leaves a complete file. asyncfem::Error if it cannot be written.
void writePvd(const std::filesystem::path& path, const std::vector<PvdEntry>& entries);

/// A frame series for ParaView: FOLDER/frame_NNNNN.vtu per frame (frame index, 5 digits
/// or more) and FOLDER/frames.pvd listing the frames written so far with their times.
/// The .pvd is rewritten (atomically) after every frame, so a run stopped at any point
/// leaves a valid collection of its finished frames.
class VtuSeriesWriter {
 public:
  /// Creates folder (and its parents) if needed; writes nothing else yet.
  explicit VtuSeriesWriter(std::filesystem::path folder, VtuEncoding encoding = VtuEncoding::binary);

  /// "frame_00042.vtu" for frame 42.
  static std::string frameFileName(std::int64_t frame);

  /// Writes frame's .vtu (rest positions + displacement and the given point arrays, see
  /// writeVtu) and the .pvd with it appended at time.
  void writeFrame(std::int64_t frame, double time, const TetMesh& mesh, const Eigen::VectorXd& displacement,
                  const std::vector<VtuArray>& pointArrays = {});
  /// Lists an already written frame file in the collection (a resumed run's earlier
  /// frames) without writing it; the .pvd is rewritten at the next writeFrame or
  /// writeCollection.
  void addExistingFrame(std::int64_t frame, double time);
  /// Rewrites the .pvd with the frames listed so far (possibly none).
  void writeCollection() const;

  const std::filesystem::path& folder() const { return folder_; }
  std::filesystem::path collectionPath() const { return folder_ / "frames.pvd"; }
  const std::vector<PvdEntry>& entries() const { return entries_; }

 private:
  std::filesystem::path folder_;
  VtuEncoding encoding_;
  std::vector<PvdEntry> entries_;
};

}  // namespace asyncfem
