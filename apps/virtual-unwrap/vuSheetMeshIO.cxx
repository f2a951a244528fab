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
#include "vuSheetMeshIO.h"

#include "itkMesh.h"
#include "itkMeshFileReader.h"
#include "itkSheetMeshAdaptor.h"
#include "vuCommands.h"

#include <vtkCellArray.h>
#include <vtkFloatArray.h>
#include <vtkIntArray.h>
#include <vtkNew.h>
#include <vtkOBJWriter.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkXMLPolyDataReader.h>
#include <vtkXMLPolyDataWriter.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <regex>

namespace vu {
namespace {
// ITK's OBJ reader parses coordinates with an input stream, which neither accepts nor
// reports "nan" or "inf"; it leaves whatever it had. Every vertex line is checked here so
// that a non-finite or unreadable coordinate is named, with its line, as bad input.
void
CheckObjVertices(const std::string & path)
{
  std::ifstream file(path);
  std::string   line;
  size_t        lineNumber = 0;
  size_t        vertex = 0;
  while (std::getline(file, line))
  {
    ++lineNumber;
    if (line.size() < 2 || line[0] != 'v' || !std::isspace(static_cast<unsigned char>(line[1])))
    {
      continue;
    }
    const char * cursor = line.c_str() + 1;
    for (int d = 0; d < 3; ++d)
    {
      char *       end = nullptr;
      const double value = std::strtod(cursor, &end);
      if (end == cursor || !std::isfinite(value))
      {
        throw UsageError(path + ":" + std::to_string(lineNumber) + ": vertex " + std::to_string(vertex + 1) +
                         (end == cursor ? " has fewer than three coordinates" : " has a non-finite coordinate"));
      }
      cursor = end;
    }
    ++vertex;
  }
}

// Legacy VTK PolyData, the part a sheet needs: POINTS, then POLYGONS (triangles), ASCII
// or BINARY (big-endian), version 2 to 4 layout. Every size a section claims is checked
// against the bytes left in the file before anything is allocated or read: both ITK's
// and VTK's legacy readers read past their buffers on a truncated binary file.
// The reading state of one legacy VTK file: every failure is one line naming the file.
class LegacyVtkReader
{
public:
  explicit LegacyVtkReader(const std::string & path)
    : m_Path(path)
    , m_In(path, std::ios::binary)
    , m_FileSize(std::filesystem::file_size(path))
  {}

  itk::SheetMesh
  Read()
  {
    std::string line, format, word, kind;
    if (!std::getline(m_In, line) || line.rfind("# vtk DataFile", 0) != 0)
    {
      Fail("not a legacy VTK file");
    }
    std::getline(m_In, line); // title
    m_In >> format >> word >> kind;
    if (!m_In || (format != "ASCII" && format != "BINARY"))
    {
      Fail("the third line must say ASCII or BINARY");
    }
    if (word != "DATASET" || kind != "POLYDATA")
    {
      Fail("not DATASET POLYDATA");
    }
    m_Binary = format == "BINARY";
    itk::SheetMesh sheet;
    bool           havePoints = false;
    while (m_In >> word)
    {
      if (word == "POINTS")
      {
        ReadPoints(sheet);
        havePoints = true;
      }
      else if (word == "POLYGONS" || word == "VERTICES" || word == "LINES" || word == "TRIANGLE_STRIPS")
      {
        long long n = 0, size = 0;
        m_In >> n >> size;
        if (!m_In || n < 0 || size < 0 || size < n)
        {
          Fail(word + " must give a cell count and a size");
        }
        std::vector<long long> values;
        ReadIntegers(size, values);
        if (word != "POLYGONS")
        {
          continue; // not part of a sheet
        }
        if (!havePoints)
        {
          Fail("POLYGONS before POINTS");
        }
        AppendTriangles(n, values, sheet);
        return sheet; // the attributes that may follow are not needed
      }
      else
      {
        break;
      }
    }
    Fail(havePoints ? "no POLYGONS" : "no POINTS");
  }

private:
  [[noreturn]] void
  Fail(const std::string & why) const
  {
    throw UsageError("cannot read a mesh from " + m_Path + ": " + why);
  }

  uintmax_t
  Remaining()
  {
    const auto at = m_In.tellg();
    return at < 0 || static_cast<uintmax_t>(at) > m_FileSize ? 0 : m_FileSize - static_cast<uintmax_t>(at);
  }

  static void
  BigEndian(const char * bytes, size_t size, void * value)
  {
    char swapped[8];
    for (size_t i = 0; i < size; ++i)
    {
      swapped[i] = bytes[size - 1 - i];
    }
    std::memcpy(value, swapped, size);
  }

  // Reads count 32-bit integers (cell sizes and point ids).
  void
  ReadIntegers(long long count, std::vector<long long> & values)
  {
    if (m_Binary)
    {
      if (static_cast<uintmax_t>(count) * 4 > Remaining())
      {
        Fail("a cell section claims more data than the file holds");
      }
      m_In.get(); // the newline before the data
      std::vector<char> bytes(static_cast<size_t>(count) * 4);
      m_In.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
      values.resize(static_cast<size_t>(count));
      for (size_t i = 0; i < values.size(); ++i)
      {
        int32_t v = 0;
        BigEndian(&bytes[4 * i], 4, &v);
        values[i] = v;
      }
    }
    else
    {
      if (static_cast<uintmax_t>(count) * 2 > Remaining() + 1)
      {
        Fail("a cell section claims more numbers than the file holds");
      }
      values.resize(static_cast<size_t>(count));
      for (auto & v : values)
      {
        m_In >> v;
      }
    }
    if (!m_In)
    {
      Fail("a cell section is cut short or holds something other than whole numbers");
    }
  }

  void
  ReadPoints(itk::SheetMesh & sheet)
  {
    long long   n = 0;
    std::string type;
    m_In >> n >> type;
    const size_t bytes = type == "float" ? 4 : type == "double" ? 8 : 0;
    if (!m_In || n <= 0 || bytes == 0)
    {
      Fail("the POINTS line must give a positive count and float or double");
    }
    if (static_cast<uintmax_t>(n) * 3 * (m_Binary ? bytes : 2) > Remaining() + 1)
    {
      Fail("POINTS claims " + std::to_string(n) + " points, more than the file holds");
    }
    sheet.Points.resize(static_cast<size_t>(3 * n));
    if (m_Binary)
    {
      m_In.get();
      std::vector<char> data(sheet.Points.size() * bytes);
      m_In.read(data.data(), static_cast<std::streamsize>(data.size()));
      for (size_t i = 0; i < sheet.Points.size(); ++i)
      {
        if (bytes == 4)
        {
          float v = 0.0f;
          BigEndian(&data[4 * i], 4, &v);
          sheet.Points[i] = v;
        }
        else
        {
          BigEndian(&data[8 * i], 8, &sheet.Points[i]);
        }
      }
    }
    else
    {
      for (double & v : sheet.Points)
      {
        m_In >> v;
      }
    }
    if (!m_In)
    {
      Fail("POINTS is cut short or holds something other than numbers");
    }
  }

  // The n triangles of a POLYGONS section's values (3, a, b, c per cell).
  void
  AppendTriangles(long long n, const std::vector<long long> & values, itk::SheetMesh & sheet) const
  {
    size_t i = 0;
    for (long long cell = 0; cell < n; ++cell)
    {
      if (i < values.size() && values[i] != 3)
      {
        Fail("a polygon is not a triangle");
      }
      if (i + 3 >= values.size())
      {
        Fail("POLYGONS holds fewer cells than it claims");
      }
      for (int k = 1; k <= 3; ++k)
      {
        if (values[i + k] < 0 || values[i + k] > std::numeric_limits<uint32_t>::max())
        {
          Fail("a triangle refers to point " + std::to_string(values[i + k]));
        }
        sheet.Triangles.push_back(static_cast<uint32_t>(values[i + k]));
      }
      i += 4;
    }
  }

  std::string     m_Path;
  std::ifstream   m_In;
  const uintmax_t m_FileSize;
  bool            m_Binary{ false };
};

itk::SheetMesh
ReadLegacyVtk(const std::string & path)
{
  return LegacyVtkReader(path).Read();
}
// Why VTK's XML reader cannot be given a file, or "": it sizes its arrays from the
// counts the XML claims (NumberOfPoints, NumberOfComponents, ...) and loops over them
// whatever the file holds. Each value takes at least one byte of the file, or of its
// compressed data at zlib's best ratio (about 1000 to 1).
std::string
VtkXmlCountProblem(const std::string & path)
{
  std::ifstream in(path, std::ios::binary);
  std::string   text(1u << 20, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<size_t>(in.gcount()));
  const size_t appended = text.find("<AppendedData");
  if (appended != std::string::npos)
  {
    text.resize(appended);
  }
  std::error_code         error;
  const double            size = static_cast<double>(std::filesystem::file_size(path, error));
  const double            holds = 1100.0 * size + 65536.0;
  static const std::regex count(
    R"re(\b(NumberOf(?:Points|Polys|Cells|Verts|Lines|Strips|Components|Tuples))\s*=\s*"([^"]*)")re");
  double points = 0.0;
  for (auto m = std::sregex_iterator(text.begin(), text.end(), count); m != std::sregex_iterator(); ++m)
  {
    const std::string name = (*m)[1];
    const std::string value = (*m)[2];
    char *            end = nullptr;
    const double      n = std::strtod(value.c_str(), &end);
    if (end == value.c_str() || *end != '\0' || !(n >= 0.0) || n != std::floor(n) ||
        (name == "NumberOfComponents" && n > 64.0) || n > holds || (name == "NumberOfComponents" && n * points > holds))
    {
      return path + ": " + name + "=\"" + value + "\" is more than the file can hold";
    }
    if (name == "NumberOfPoints")
    {
      points = n;
    }
  }
  return {};
}
} // namespace

vtkSmartPointer<vtkPolyData>
SheetMeshToPolyData(const itk::SheetMesh & mesh)
{
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(static_cast<vtkIdType>(mesh.GetNumberOfPoints()));
  for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
  {
    points->SetPoint(static_cast<vtkIdType>(i), &mesh.Points[3 * i]);
  }
  vtkNew<vtkCellArray> triangles;
  for (size_t t = 0; t < mesh.GetNumberOfTriangles(); ++t)
  {
    const vtkIdType ids[3] = { mesh.Triangles[3 * t], mesh.Triangles[3 * t + 1], mesh.Triangles[3 * t + 2] };
    triangles->InsertNextCell(3, ids);
  }
  auto polyData = vtkSmartPointer<vtkPolyData>::New();
  polyData->SetPoints(points);
  polyData->SetPolys(triangles);
  return polyData;
}


itk::SheetMesh
ReadSheetMesh(const std::string & path)
{
  if (!std::filesystem::is_regular_file(path))
  {
    throw UsageError("mesh file not found: " + path);
  }
  itk::SheetMesh sheet;
  std::string    extension = std::filesystem::path(path).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(), [](unsigned char c) {
    return static_cast<char>(std::tolower(c));
  });
  if (extension == ".vtk")
  {
    sheet = ReadLegacyVtk(path);
  }
  else if (extension == ".vtp")
  {
    const std::string problem = VtkXmlCountProblem(path);
    if (!problem.empty())
    {
      throw UsageError(problem);
    }
    vtkNew<vtkXMLPolyDataReader> reader;
    reader->SetFileName(path.c_str());
    reader->Update();
    vtkPolyData * polyData = reader->GetOutput();
    if (reader->GetErrorCode() != 0 || polyData == nullptr || polyData->GetNumberOfPoints() == 0)
    {
      throw UsageError("cannot read a mesh from " + path);
    }
    for (vtkIdType i = 0; i < polyData->GetNumberOfPoints(); ++i)
    {
      double p[3];
      polyData->GetPoint(i, p);
      sheet.Points.insert(sheet.Points.end(), { p[0], p[1], p[2] });
    }
    vtkCellArray * polys = polyData->GetPolys();
    polys->InitTraversal();
    vtkIdType         count = 0;
    const vtkIdType * ids = nullptr;
    while (polys->GetNextCell(count, ids))
    {
      if (count != 3)
      {
        throw UsageError(path + ": a polygon is not a triangle");
      }
      sheet.Triangles.insert(sheet.Triangles.end(), { uint32_t(ids[0]), uint32_t(ids[1]), uint32_t(ids[2]) });
    }
    auto * rows = vtkIntArray::SafeDownCast(polyData->GetPointData()->GetArray("GridRow"));
    auto * columns = vtkIntArray::SafeDownCast(polyData->GetPointData()->GetArray("GridColumn"));
    if (rows != nullptr && columns != nullptr)
    {
      for (vtkIdType i = 0; i < polyData->GetNumberOfPoints(); ++i)
      {
        sheet.GridIndex.insert(sheet.GridIndex.end(), { rows->GetValue(i), columns->GetValue(i) });
        sheet.GridRows = std::max(sheet.GridRows, rows->GetValue(i) + 1);
        sheet.GridColumns = std::max(sheet.GridColumns, columns->GetValue(i) + 1);
      }
    }
  }
  else
  {
    using MeshType = itk::Mesh<float, 3>;
    auto reader = itk::MeshFileReader<MeshType>::New();
    reader->SetFileName(path);
    try
    {
      reader->Update();
      sheet = itk::MeshToSheetMesh(reader->GetOutput());
    }
    catch (const itk::ExceptionObject & e)
    {
      throw UsageError("cannot read a mesh from " + path + ": " + e.GetDescription());
    }
    if (extension == ".obj")
    {
      CheckObjVertices(path);
    }
  }
  try
  {
    sheet.Validate(path);
  }
  catch (const itk::ExceptionObject & e)
  {
    throw UsageError(e.GetDescription());
  }
  return sheet;
}

void
WriteSheetMeshObj(const std::string &         path,
                  const itk::SheetMesh &      mesh,
                  const std::vector<double> & textureCoordinates,
                  const std::string &         textureFileName)
{
  vtkSmartPointer<vtkPolyData> polyData = SheetMeshToPolyData(mesh);
  if (!textureCoordinates.empty())
  {
    vtkNew<vtkFloatArray> tcoords;
    tcoords->SetName("TextureCoordinates");
    tcoords->SetNumberOfComponents(2);
    tcoords->SetNumberOfTuples(static_cast<vtkIdType>(mesh.GetNumberOfPoints()));
    for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      tcoords->SetTuple2(static_cast<vtkIdType>(i), textureCoordinates[2 * i], textureCoordinates[2 * i + 1]);
    }
    polyData->GetPointData()->SetTCoords(tcoords);
  }
  vtkNew<vtkOBJWriter> writer;
  writer->SetInputData(polyData);
  writer->SetFileName(path.c_str());
  if (!textureFileName.empty())
  {
    writer->SetTextureFileName(textureFileName.c_str());
  }
  if (writer->Write() != 1)
  {
    throw UsageError("cannot write " + path);
  }
}

void
WriteSheetMeshVtp(const std::string &        path,
                  const itk::SheetMesh &     mesh,
                  const std::vector<float> & pointScalars,
                  const std::string &        scalarName)
{
  vtkSmartPointer<vtkPolyData> polyData = SheetMeshToPolyData(mesh);
  if (mesh.IsGridStructured())
  {
    vtkNew<vtkIntArray> rows, columns;
    rows->SetName("GridRow");
    columns->SetName("GridColumn");
    for (size_t i = 0; i < mesh.GetNumberOfPoints(); ++i)
    {
      rows->InsertNextValue(mesh.GridIndex[2 * i]);
      columns->InsertNextValue(mesh.GridIndex[2 * i + 1]);
    }
    polyData->GetPointData()->AddArray(rows);
    polyData->GetPointData()->AddArray(columns);
  }
  if (!pointScalars.empty())
  {
    vtkNew<vtkFloatArray> scalars;
    scalars->SetName(scalarName.c_str());
    for (float v : pointScalars)
    {
      scalars->InsertNextValue(v);
    }
    polyData->GetPointData()->SetScalars(scalars);
  }
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(polyData);
  writer->SetFileName(path.c_str());
  writer->SetDataModeToBinary();
  if (writer->Write() != 1)
  {
    throw UsageError("cannot write " + path);
  }
}
} // namespace vu
