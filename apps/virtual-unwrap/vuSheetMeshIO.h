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
#ifndef vuSheetMeshIO_h
#define vuSheetMeshIO_h

#include "itkSheetMesh.h"

#include <vtkPolyData.h>
#include <vtkSmartPointer.h>

#include <string>
#include <vector>

namespace vu {
/** Reads a triangle mesh: VTK XML PolyData (.vtp) and legacy VTK PolyData (.vtk) through
 * VTK, with the sheet grid when the file carries the point arrays GridRow and GridColumn;
 * anything else ITK's mesh IO reads (OBJ, OFF, BYU, GIFTI) through ITK. Throws
 * vu::UsageError naming the file. */
itk::SheetMesh
ReadSheetMesh(const std::string & path);

/** The mesh as VTK PolyData: double-precision points and its triangles. */
vtkSmartPointer<vtkPolyData>
SheetMeshToPolyData(const itk::SheetMesh & mesh);

/** Writes a Wavefront OBJ (through VTK's vtkOBJWriter). With texture coordinates (u, v per
 * point, in [0, 1]) and a texture file name, a material file of the same base name is
 * written beside it and the OBJ refers to it. */
void
WriteSheetMeshObj(const std::string &         path,
                  const itk::SheetMesh &      mesh,
                  const std::vector<double> & textureCoordinates = {},
                  const std::string &         textureFileName = {});

/** Writes VTK XML PolyData with the sheet grid (GridRow, GridColumn) and, when given, one
 * scalar per point under the given name. */
void
WriteSheetMeshVtp(const std::string &        path,
                  const itk::SheetMesh &     mesh,
                  const std::vector<float> & pointScalars = {},
                  const std::string &        scalarName = {});
} // namespace vu

#endif
