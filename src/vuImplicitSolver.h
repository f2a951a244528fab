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
#ifndef vuImplicitSolver_h
#define vuImplicitSolver_h

#include "itkMassSpringSystem.h"
#include "itkMultiThreaderBase.h"
#include "itk_eigen.h"
#include ITK_EIGEN(Sparse)
#include ITK_EIGEN(SparseCholesky)
#ifdef VU_HAVE_CHOLMOD
#  include ITK_EIGEN(CholmodSupport)
#endif

#include <cstdint>
#include <vector>

namespace itk {
/** The implicit integrator's factorised system matrix and the particles it solves for.
 * The matrix (M / h^2 + L, symmetric positive definite) is factorised by SuiteSparse's
 * CHOLMOD where the library was built with it (supernodal Cholesky, fill-reducing
 * ordering chosen by CHOLMOD among AMD and METIS), otherwise by Eigen's simplicial LDL^T.
 * The symbolic analysis depends only on which particles are free and which springs join
 * them, so a new time step or stiffness refactorises the values alone. */
struct MassSpringSystem::ImplicitSolver
{
  using SparseMatrix = Eigen::SparseMatrix<double>;
#ifdef VU_HAVE_CHOLMOD
  using Factorisation = Eigen::CholmodDecomposition<SparseMatrix, Eigen::Lower>;
#else
  using Factorisation = Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower>;
#endif
  Factorisation         factorisation;
  std::vector<int32_t>  freeIndex; // particle -> row, or -1 when locked
  std::vector<uint32_t> freeParticles;
  bool                  valid{ false };    // the numeric factorisation matches the system
  bool                  analysed{ false }; // the symbolic analysis matches the free set

  // Assembles M / h^2 plus the springs' Laplacian over the free particles and factorises
  // it (the symbolic analysis only when the free set changed); throws when it fails.
  void
  Factorise(const MassSpringSystem & system, double invH2);
  // Kept for the engine's lifetime: creating a threader per force loop costs more than a
  // small system's whole step.
  MultiThreaderBase::Pointer threader;

  MultiThreaderBase *
  Threader(unsigned int workUnits)
  {
    if (threader.IsNull())
    {
      threader = MultiThreaderBase::New();
      if (workUnits > 0)
      {
        threader->SetMaximumNumberOfThreads(workUnits);
        threader->SetNumberOfWorkUnits(workUnits);
      }
    }
    return threader.GetPointer();
  }
};
} // end namespace itk

#endif
