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
// The layer stack's combinations into textures (LayerStackTexture::Combine and the
// readable-texture candidates): every combination of a stack in one pass over it.
#include "vuCombineLayers.h"
#include "itkMultiThreaderBase.h"
#include "vuVectorClones.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace itk {
namespace {
constexpr float NaN = std::numeric_limits<float>::quiet_NaN();

// One combination's layers (all of them, or one half of a stack sampled on both sides), its
// TextureLayers and its core.
struct CombinationPlan
{
  std::vector<SizeValueType> Index, Core;
  TextureLayers              Layers;
};

std::vector<CombinationPlan>
PlanCombinations(unsigned int                                  numberOfLayers,
                 double                                        layerSpacing,
                 double                                        focus,
                 TextureLayersEnums::Side                      stackSide,
                 TextureLayersEnums::Filter                    filter,
                 double                                        gaussianSigma,
                 const std::vector<detail::LayerCombination> & combinations)
{
  std::vector<CombinationPlan> plans;
  for (const detail::LayerCombination & c : combinations)
  {
    const auto side = c.Side;
    detail::CheckLayerParameter(c.CoreWidth, true, "Combine", "the core width");
    std::vector<SizeValueType> index;
    unsigned int               count = numberOfLayers;
    if (side == stackSide)
    {
      for (unsigned int k = 0; k < numberOfLayers; ++k)
      {
        index.push_back(k);
      }
    }
    else if (stackSide == TextureLayersEnums::Side::Both && numberOfLayers % 2 == 1)
    {
      const unsigned int centre = (numberOfLayers - 1) / 2;
      count = centre + 1;
      for (unsigned int k = 0; k < count; ++k)
      {
        index.push_back(side == TextureLayersEnums::Side::Positive ? centre + k : centre - k);
      }
    }
    else
    {
      itkGenericExceptionMacro(<< "LayerStackTexture::Combine: cannot take the " << side << " layers of a stack of "
                               << numberOfLayers << " layers sampled on side " << stackSide
                               << " (a stack sampled on both sides with an odd number of layers splits in halves)");
    }
    CombinationPlan plan{ index, {}, TextureLayers(count, layerSpacing, focus, side, filter, gaussianSigma) };
    if (c.CoreWidth > 0.0)
    {
      for (unsigned int k = 0; k < count; ++k)
      {
        if (std::abs(plan.Layers.GetOffsets()[k] - focus) <= c.CoreWidth + 1e-9 * layerSpacing)
        {
          plan.Core.push_back(k);
        }
      }
      if (plan.Core.empty())
      {
        itkGenericExceptionMacro(<< "LayerStackTexture::Combine: no layer lies within the core width " << c.CoreWidth
                                 << " of the focus");
      }
    }
    plans.push_back(std::move(plan));
  }
  return plans;
}

// The row loops of CombineExtremeRows, compiled twice on x86-64 with GCC, for AVX2 and for
// the baseline (SSE2), and picked by the loader: the same operations, value for value. Any
// non-finite sample makes a pixel's check NaN (v - v is 0 for finite v only).
VU_VECTOR_CLONES void
StartExtremeRow(const float * __restrict first,
                SizeValueType columns,
                float * __restrict extremum,
                float * __restrict check)
{
  for (SizeValueType x = 0; x < columns; ++x)
  {
    extremum[x] = first[x];
    check[x] = first[x] - first[x];
  }
}

VU_VECTOR_CLONES void
AddToExtremeRow(const float * __restrict layer,
                SizeValueType columns,
                bool          largest,
                float * __restrict extremum,
                float * __restrict check)
{
  if (largest)
  {
    for (SizeValueType x = 0; x < columns; ++x)
    {
      extremum[x] = extremum[x] < layer[x] ? layer[x] : extremum[x];
      check[x] += layer[x] - layer[x];
    }
  }
  else
  {
    for (SizeValueType x = 0; x < columns; ++x)
    {
      extremum[x] = layer[x] < extremum[x] ? layer[x] : extremum[x];
      check[x] += layer[x] - layer[x];
    }
  }
}

VU_VECTOR_CLONES void
AddToCoreRow(const float * __restrict layer, SizeValueType columns, double * __restrict core)
{
  for (SizeValueType x = 0; x < columns; ++x)
  {
    core[x] += layer[x];
  }
}

VU_VECTOR_CLONES void
FinishExtremeRow(const float * __restrict extremum,
                 const float * __restrict check,
                 const double * __restrict core,
                 double        coreCount,
                 SizeValueType columns,
                 float * __restrict target)
{
  for (SizeValueType x = 0; x < columns; ++x)
  {
    target[x] = check[x] == 0.0f ? static_cast<float>(extremum[x] - core[x] / coreCount) : NaN;
  }
}

// The largest or smallest sample (the usual filters) whole rows at a time, each layer's row
// read in turn: the same values as CombineSampleBySample.
void
CombineExtremeRows(const Image<float, 3> *              stack,
                   bool                                 largest,
                   const std::vector<CombinationPlan> & plans,
                   const std::vector<float *> &         out)
{
  const auto          size = stack->GetBufferedRegion().GetSize();
  const float *       in = stack->GetBufferPointer();
  const SizeValueType plane = size[0] * size[1];
  const auto          columns = static_cast<SizeValueType>(size[0]);
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[1],
    [&](SizeValueType row) {
      std::vector<float>  extremumRow(columns), checkRow(columns);
      std::vector<double> coreRow(columns);
      float * __restrict extremum = extremumRow.data();
      float * __restrict check = checkRow.data();
      double * __restrict core = coreRow.data();
      for (size_t c = 0; c < plans.size(); ++c)
      {
        const CombinationPlan & plan = plans[c];
        const float *           first = in + plan.Index[0] * plane + row * columns;
        StartExtremeRow(first, columns, extremum, check);
        for (size_t k = 1; k < plan.Index.size(); ++k)
        {
          AddToExtremeRow(in + plan.Index[k] * plane + row * columns, columns, largest, extremum, check);
        }
        std::fill(core, core + columns, 0.0);
        for (const SizeValueType k : plan.Core)
        {
          AddToCoreRow(in + plan.Index[k] * plane + row * columns, columns, core);
        }
        const double coreCount = plan.Core.empty() ? 1.0 : static_cast<double>(plan.Core.size());
        FinishExtremeRow(extremum, check, core, coreCount, columns, out[c] + row * columns);
      }
    },
    nullptr);
}

// Row by row in parallel, each pixel's samples read once for every combination.
void
CombineSampleBySample(const Image<float, 3> *              stack,
                      const std::vector<CombinationPlan> & plans,
                      const std::vector<float *> &         out)
{
  const auto          size = stack->GetBufferedRegion().GetSize();
  const auto          numberOfLayers = static_cast<unsigned int>(size[2]);
  const float *       in = stack->GetBufferPointer();
  const SizeValueType plane = size[0] * size[1];
  MultiThreaderBase::New()->ParallelizeArray(
    0,
    size[1],
    [&](SizeValueType row) {
      std::vector<float> all(numberOfLayers), samples(numberOfLayers);
      std::vector<char>  finite(numberOfLayers);
      for (SizeValueType p = row * size[0]; p < (row + 1) * size[0]; ++p)
      {
        for (unsigned int k = 0; k < numberOfLayers; ++k)
        {
          all[k] = in[k * plane + p];
          finite[k] = std::isfinite(all[k]);
        }
        for (size_t c = 0; c < plans.size(); ++c)
        {
          const CombinationPlan & plan = plans[c];
          bool                    whole = true;
          for (size_t k = 0; k < plan.Index.size(); ++k)
          {
            samples[k] = all[plan.Index[k]];
            whole = whole && finite[plan.Index[k]];
          }
          if (!whole)
          {
            out[c][p] = NaN;
            continue;
          }
          double coreMean = 0.0;
          for (SizeValueType k : plan.Core)
          {
            coreMean += samples[k];
          }
          coreMean = plan.Core.empty() ? 0.0 : coreMean / plan.Core.size();
          out[c][p] = static_cast<float>(plan.Layers.Combine(samples.data()) - coreMean);
        }
      }
    },
    nullptr);
}
} // namespace

std::vector<Image<float, 2>::Pointer>
detail::CombineLayers(const Image<float, 3> *               stack,
                      unsigned int                          numberOfLayers,
                      double                                layerSpacing,
                      double                                focus,
                      TextureLayersEnums::Side              stackSide,
                      TextureLayersEnums::Filter            filter,
                      double                                gaussianSigma,
                      const std::vector<LayerCombination> & combinations)
{
  if (stack == nullptr)
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::Combine: no layer stack");
  }
  const auto size = stack->GetBufferedRegion().GetSize();
  if (stack->GetBufferedRegion() != stack->GetLargestPossibleRegion() || size[2] != numberOfLayers)
  {
    itkGenericExceptionMacro(<< "LayerStackTexture::Combine: the stack has " << size[2] << " layers, not "
                             << numberOfLayers << ", or is not fully buffered");
  }
  const std::vector<CombinationPlan> plans =
    PlanCombinations(numberOfLayers, layerSpacing, focus, stackSide, filter, gaussianSigma, combinations);
  std::vector<Image<float, 2>::Pointer> textures;
  std::vector<float *>                  out;
  for (size_t c = 0; c < plans.size(); ++c)
  {
    textures.push_back(detail::NewLayerTexture(stack));
    out.push_back(textures.back()->GetBufferPointer());
  }
  if (filter == TextureLayersEnums::Filter::Max || filter == TextureLayersEnums::Filter::Min)
  {
    CombineExtremeRows(stack, filter == TextureLayersEnums::Filter::Max, plans, out);
  }
  else
  {
    CombineSampleBySample(stack, plans, out);
  }
  return textures;
}

} // end namespace itk
