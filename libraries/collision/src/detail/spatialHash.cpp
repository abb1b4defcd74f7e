// SPDX-License-Identifier: BSD-3-Clause
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <detail/boxPairs.hpp>

namespace asyncfem::detail {

namespace {

/// A uniform grid over the boxes' common bounding box. Cell (i, j, k) covers
/// origin + cellSize * [(i, j, k), (i + 1, j + 1, k + 1)) (the last cell of an axis also
/// holds its upper bound); its key is i + n_x (j + n_y k), below cellCount().
struct Grid {
  Eigen::Array3d origin;
  double cellSize = 1.0;
  Eigen::Array3i cells = Eigen::Array3i::Ones();  ///< cells per axis

  Eigen::Array3i cell(const Eigen::Array3d& point) const {
    return ((point - origin) / cellSize).floor().cast<int>().max(0).min(cells - 1);
  }
  std::uint64_t key(const Eigen::Array3i& cell) const {
    return static_cast<std::uint64_t>(cell.x()) +
           (static_cast<std::uint64_t>(cells.x()) *
            (static_cast<std::uint64_t>(cell.y()) + (static_cast<std::uint64_t>(cells.y()) * cell.z())));
  }
  std::uint64_t cellCount() const { return static_cast<std::uint64_t>(cells.cast<std::int64_t>().prod()); }
};

constexpr int kMaxCellsPerAxis = 1 << 20;

/// The cell size is the mean largest side of the boxes, so a typical box covers 1 to 8
/// cells, grown where needed to keep under kMaxCellsPerAxis cells per axis.
Grid makeGrid(const BoxSet& first, const BoxSet& second) {
  Grid grid;
  const Eigen::Array3d low = first.min.rowwise().minCoeff().array().min(second.min.rowwise().minCoeff().array());
  const Eigen::Array3d high = first.max.rowwise().maxCoeff().array().max(second.max.rowwise().maxCoeff().array());
  grid.origin = low;
  const double sides =
      (first.max - first.min).colwise().maxCoeff().sum() + (second.max - second.min).colwise().maxCoeff().sum();
  const double meanSide = sides / static_cast<double>(first.size() + second.size());
  const double extent = (high - low).maxCoeff();
  grid.cellSize = std::max(meanSide, extent / (kMaxCellsPerAxis - 1));
  if (!(grid.cellSize > 0.0)) grid.cellSize = 1.0;  // every box is the same point
  grid.cells = ((high - low) / grid.cellSize).floor().cast<int>().max(0).min(kMaxCellsPerAxis - 1) + 1;
  return grid;
}

struct CellEntry {
  std::uint64_t key;
  int box;
  bool operator<(const CellEntry& other) const { return key != other.key ? key < other.key : box < other.box; }
};

/// A box touching more cells than this is "large": it is kept out of the grid and tested
/// against every box of the other set, so that a few boxes much larger than the cell (a
/// coarse obstacle under a fine body) cost a loop each instead of millions of cell entries.
constexpr long long kLargeBoxCells = 64;

/// The boxes in the grid as (cell, box) for every cell each touches, sorted by cell, and
/// the large boxes.
struct GridEntries {
  std::vector<CellEntry> entries;
  std::vector<int> largeBoxes;
  std::vector<char> isLarge;
  Eigen::Matrix3Xi lowCells;  ///< per box, the cell of its low corner
};

/// Sorts entries made in ascending box order by key, stably, so that they end sorted by
/// (key, box): least-significant-digit radix sort, 11 bits a pass, over the bits the
/// grid's keys use (a pass fewer than a comparison sort's log n for every grid this
/// library builds below 2^33 cells; above, std::sort).
void sortEntries(std::vector<CellEntry>& entries, std::uint64_t cellCount) {
  constexpr int kDigitBits = 11;
  constexpr std::size_t kBuckets = std::size_t{1} << kDigitBits;
  int bits = 1;
  while (bits < 64 && (std::uint64_t{1} << bits) < cellCount) ++bits;
  if (bits > 3 * kDigitBits) {
    std::sort(entries.begin(), entries.end());
    return;
  }
  std::vector<CellEntry> buffer(entries.size());
  std::vector<std::size_t> start(kBuckets + 1);
  for (int shift = 0; shift < bits; shift += kDigitBits) {
    std::fill(start.begin(), start.end(), 0);
    for (const CellEntry& entry : entries) ++start[((entry.key >> shift) & (kBuckets - 1)) + 1];
    for (std::size_t d = 0; d < kBuckets; ++d) start[d + 1] += start[d];
    for (const CellEntry& entry : entries) buffer[start[(entry.key >> shift) & (kBuckets - 1)]++] = entry;
    entries.swap(buffer);
  }
}

GridEntries cellEntries(const BoxSet& boxes, const Grid& grid) {
  GridEntries result;
  result.entries.reserve(4 * static_cast<std::size_t>(boxes.size()));
  result.isLarge.assign(static_cast<std::size_t>(boxes.size()), 0);
  result.lowCells.resize(3, boxes.size());
  for (int b = 0; b < boxes.size(); ++b) {
    const Eigen::Array3i low = grid.cell(boxes.min.col(b).array());
    result.lowCells.col(b) = low.matrix();
    const Eigen::Array3i high = grid.cell(boxes.max.col(b).array());
    if ((high - low + 1).cast<long long>().prod() > kLargeBoxCells) {
      result.largeBoxes.push_back(b);
      result.isLarge[static_cast<std::size_t>(b)] = 1;
      continue;
    }
    for (int k = low.z(); k <= high.z(); ++k)
      for (int j = low.y(); j <= high.y(); ++j)
        for (int i = low.x(); i <= high.x(); ++i) result.entries.push_back({grid.key({i, j, k}), b});
  }
  sortEntries(result.entries, grid.cellCount());
  return result;
}

/// Whether `key` is the cell of the low corner of the boxes' intersection: the one cell of
/// all those both boxes touch that reports the pair, so that no pair is reported twice.
/// Cells are monotone per axis, so that cell is the larger of the two low corners' cells.
bool reportingCell(std::uint64_t key, const GridEntries& first, int i, const GridEntries& second, int j,
                   const Grid& grid) {
  return grid.key(first.lowCells.col(i).array().max(second.lowCells.col(j).array())) == key;
}

std::size_t rangeEnd(const std::vector<CellEntry>& entries, std::size_t begin) {
  std::size_t end = begin + 1;
  while (end < entries.size() && entries[end].key == entries[begin].key) ++end;
  return end;
}

}  // namespace

BoxPairs spatialHashPairs(const BoxSet& first, const BoxSet& second) {
  BoxPairs pairs;
  if (first.size() == 0 || second.size() == 0) return pairs;
  const Grid grid = makeGrid(first, second);
  const GridEntries firstGrid = cellEntries(first, grid);
  const GridEntries secondGrid = cellEntries(second, grid);
  // Pairs with a large box: each large box of the first set against every box of the
  // second, each large box of the second against the first set's boxes in the grid.
  for (const int i : firstGrid.largeBoxes)
    for (int j = 0; j < second.size(); ++j)
      if (boxesOverlap(first, i, second, j)) pairs.emplace_back(i, j);
  for (const int j : secondGrid.largeBoxes)
    for (int i = 0; i < first.size(); ++i)
      if (!firstGrid.isLarge[static_cast<std::size_t>(i)] && boxesOverlap(first, i, second, j))
        pairs.emplace_back(i, j);
  const std::vector<CellEntry>& firstEntries = firstGrid.entries;
  const std::vector<CellEntry>& secondEntries = secondGrid.entries;
  std::size_t a = 0, b = 0;
  while (a < firstEntries.size() && b < secondEntries.size()) {
    if (firstEntries[a].key < secondEntries[b].key) {
      a = rangeEnd(firstEntries, a);
    } else if (secondEntries[b].key < firstEntries[a].key) {
      b = rangeEnd(secondEntries, b);
    } else {
      const std::uint64_t key = firstEntries[a].key;
      const std::size_t aEnd = rangeEnd(firstEntries, a);
      const std::size_t bEnd = rangeEnd(secondEntries, b);
      for (std::size_t p = a; p < aEnd; ++p) {
        const int i = firstEntries[p].box;
        for (std::size_t q = b; q < bEnd; ++q) {
          const int j = secondEntries[q].box;
          if (boxesOverlap(first, i, second, j) && reportingCell(key, firstGrid, i, secondGrid, j, grid))
            pairs.emplace_back(i, j);
        }
      }
      a = aEnd;
      b = bEnd;
    }
  }
  return pairs;
}

BoxPairs spatialHashSelfPairs(const BoxSet& boxes) {
  BoxPairs pairs;
  if (boxes.size() == 0) return pairs;
  const Grid grid = makeGrid(boxes, boxes);
  const GridEntries gridEntries = cellEntries(boxes, grid);
  // Pairs with a large box, each once: a large box i against every other box j, except a
  // large j < i (that pair came with j).
  for (const int i : gridEntries.largeBoxes) {
    for (int j = 0; j < boxes.size(); ++j) {
      if (j == i || (gridEntries.isLarge[static_cast<std::size_t>(j)] && j < i)) continue;
      if (boxesOverlap(boxes, i, boxes, j)) pairs.emplace_back(std::min(i, j), std::max(i, j));
    }
  }
  const std::vector<CellEntry>& entries = gridEntries.entries;
  for (std::size_t begin = 0; begin < entries.size();) {
    const std::size_t end = rangeEnd(entries, begin);
    const std::uint64_t key = entries[begin].key;
    // Entries of one cell are sorted by box, so p < q gives i < j.
    for (std::size_t p = begin; p < end; ++p) {
      const int i = entries[p].box;
      for (std::size_t q = p + 1; q < end; ++q) {
        const int j = entries[q].box;
        if (boxesOverlap(boxes, i, boxes, j) && reportingCell(key, gridEntries, i, gridEntries, j, grid))
          pairs.emplace_back(i, j);
      }
    }
    begin = end;
  }
  return pairs;
}

}  // namespace asyncfem::detail
