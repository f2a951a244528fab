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
#include "vuSolverThreads.h"

#include <cstdlib>
#include <dlfcn.h>
#include <initializer_list>

namespace vu {
namespace {
// A library among `names` already loaded by the process that exports `symbol`.
void *
LoadedLibraryWith(std::initializer_list<const char *> names, const char * symbol)
{
  for (const char * name : names)
  {
    if (void * handle = dlopen(name, RTLD_LAZY | RTLD_NOLOAD))
    {
      if (dlsym(handle, symbol) != nullptr)
      {
        return handle;
      }
      dlclose(handle);
    }
  }
  return nullptr;
}
} // namespace

SolverThreads::SolverThreads()
{
  if (std::getenv("OPENBLAS_NUM_THREADS") == nullptr)
  {
    static void * const blas = LoadedLibraryWith({ "libopenblas.so.0", "libblas.so.3" }, "openblas_set_num_threads");
    if (blas != nullptr)
    {
      auto set = reinterpret_cast<void (*)(int)>(dlsym(blas, "openblas_set_num_threads"));
      auto get = reinterpret_cast<int (*)()>(dlsym(blas, "openblas_get_num_threads"));
      if (set != nullptr && get != nullptr)
      {
        m_PreviousBlasThreads = get();
        if (m_PreviousBlasThreads > 1)
        {
          m_SetBlasThreads = set;
          m_SetBlasThreads(1);
        }
      }
    }
  }
  if (std::getenv("OMP_DYNAMIC") == nullptr && std::getenv("OMP_THREAD_LIMIT") == nullptr)
  {
    static void * const openMp = LoadedLibraryWith({ "libgomp.so.1", "libomp.so.5", "libomp.so" }, "omp_set_dynamic");
    if (openMp != nullptr)
    {
      auto set = reinterpret_cast<void (*)(int)>(dlsym(openMp, "omp_set_dynamic"));
      auto get = reinterpret_cast<int (*)()>(dlsym(openMp, "omp_get_dynamic"));
      if (set != nullptr && get != nullptr)
      {
        m_PreviousDynamic = get();
        if (m_PreviousDynamic == 0)
        {
          m_SetDynamic = set;
          m_SetDynamic(1);
        }
      }
    }
  }
}

SolverThreads::~SolverThreads()
{
  if (m_SetBlasThreads != nullptr)
  {
    m_SetBlasThreads(m_PreviousBlasThreads);
  }
  if (m_SetDynamic != nullptr)
  {
    m_SetDynamic(m_PreviousDynamic);
  }
}
} // namespace vu
