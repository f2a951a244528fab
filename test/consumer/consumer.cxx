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
#include "itkFlatteningDistortionCalculator.h"

#include <iostream>

int
main()
{
  itk::SheetMesh surface;
  surface.Points = { 0, 0, 0, 1, 0, 0, 0, 1, 0 };
  surface.Triangles = { 0, 1, 2 };
  itk::SheetMesh flat = surface;
  flat.Points[3] = 2.0; // stretch one edge to twice its length
  auto calculator = itk::FlatteningDistortionCalculator::New();
  calculator->SetSurfaceMesh(surface);
  calculator->SetFlatMesh(flat);
  calculator->Compute();
  std::cout << "edge strain max " << calculator->GetEdgeStrainMax() << std::endl;
  return calculator->GetEdgeStrainMax() == 1.0 ? 0 : 1;
}
