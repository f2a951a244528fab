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
#include "vuBlasThreads.h"

#include <cstdlib>
#include <dlfcn.h>
#include <initializer_list>

namespace vu {
namespace {
// OpenBLAS's own entry points, looked up in the BLAS already loaded by the process (as a
// dependency of CHOLMOD): the library is not linked against OpenBLAS itself.
void *
LoadedOpenBlas()
{
  for (const char * name : { "libopenblas.so.0", "libblas.so.3" })
  {
    if (void * handle = dlopen(name, RTLD_LAZY | RTLD_NOLOAD))
    {
      if (dlsym(handle, "openblas_set_num_threads") != nullptr)
      {
        return handle;
      }
      dlclose(handle);
    }
  }
  return nullptr;
}
} // namespace

SingleThreadedBlas::SingleThreadedBlas()
{
  if (std::getenv("OPENBLAS_NUM_THREADS") != nullptr)
  {
    return;
  }
  static void * const handle = LoadedOpenBlas();
  if (handle == nullptr)
  {
    return;
  }
  auto set = reinterpret_cast<void (*)(int)>(dlsym(handle, "openblas_set_num_threads"));
  auto get = reinterpret_cast<int (*)()>(dlsym(handle, "openblas_get_num_threads"));
  if (set == nullptr || get == nullptr)
  {
    return;
  }
  m_Previous = get();
  if (m_Previous > 1)
  {
    m_Set = set;
    m_Set(1);
  }
}

SingleThreadedBlas::~SingleThreadedBlas()
{
  if (m_Set != nullptr)
  {
    m_Set(m_Previous);
  }
}
} // namespace vu
