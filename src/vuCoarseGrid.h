/*=========================================================================
 *
 *  Copyright NumFOCUS
 *
 *  Licensed under the Apache License, Version 2.0 (the "License");
 *  you may not use this file except in compliance with the License.
 *  You may obtain a copy of the License at
 *
 *         http://www.apache.org/licenses/LICENSE-2.0.txt
 *
 *  Unless required by applicable law or agreed to in writing, software
 *  distributed under the License is distributed on an "AS IS" BASIS,
 *  WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
 *  See the License for the specific language governing permissions and
 *  limitations under the License.
 *
 *=========================================================================*/
#ifndef vuCoarseGrid_h
#define vuCoarseGrid_h

#include "itkSheetMesh.h"

#include <cstdint>
#include <vector>

namespace itk {
/** Coarse-to-fine simulation of a grid-structured sheet mesh: the simulation runs on every
 * n-th row and column, and its flat result is carried back to every point. */
namespace CoarseToFine {
/** Dense (row, column) -> point lookup of a grid-structured mesh; -1 where no point. Throws
 * itk::ExceptionObject on a grid index outside the grid. */
std::vector<int64_t>
GridLookup(const SheetMesh & mesh);

/** Every `factor`-th row and column of a grid mesh (and the last ones), as a grid mesh of its
 * own; `fineIds` receives each coarse point's id in `mesh`. */
SheetMesh
CoarseGrid(const SheetMesh & mesh, unsigned int factor, std::vector<uint32_t> & fineIds);

/** Flat positions (x, y, 0 per point) of every point of `mesh` from those of its coarse grid
 * (`coarseFlat`, CoarseGrid(mesh, factor)'s points): bilinear in (row, column) inside
 * complete coarse cells, harmonic (a sparse Laplace solve with the known points fixed)
 * elsewhere. */
std::vector<double>
Prolong(const SheetMesh & mesh, const SheetMesh & coarse, unsigned int factor, const std::vector<double> & coarseFlat);
} // namespace CoarseToFine
} // end namespace itk

#endif
