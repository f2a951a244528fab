# One source of truth for the module's dependencies: read by ITK's module system when the
# module sits in an ITK build tree (Modules/Remote, wheel builds) and by
# cmake/VirtualUnwrappingStandalone.cmake when building against an installed ITK.
get_filename_component(MY_CURRENT_DIR "${CMAKE_CURRENT_LIST_FILE}" PATH)
file(READ "${MY_CURRENT_DIR}/README.md" DOCUMENTATION)

itk_module(VirtualUnwrapping
  ENABLE_SHARED
  DEPENDS
    ITKCommon
    ITKEigen3
    ITKIOImageBase
    ITKIOGDCM
    ITKGDCM
    ITKIOTIFF
    ITKIONRRD
    ITKIOMeta
    ITKIONIFTI
    ITKIOHDF5
    ITKIOPNG
    ITKIOMeshBase
    ITKIOMeshVTK
    ITKIOMeshOBJ
    ITKMesh
    ITKQuadEdgeMesh
    ITKImageGrid
    ITKImageFunction
    ITKImageIntensity
    ITKImageNoise
    ITKImageFeature
    ITKImageGradient
    ITKImageSources
    ITKDeconvolution
    ITKSmoothing
    ITKThresholding
    ITKImageStatistics
    ITKConnectedComponents
    ITKBinaryMathematicalMorphology
    ITKMathematicalMorphology
    ITKDistanceMap
    ITKSpatialObjects
    ITKRegistrationMethodsv4
    ITKMetricsv4
    ITKOptimizersv4
    ITKTransform
  TEST_DEPENDS
    ITKTestKernel
    ITKGoogleTest
    ITKQuadEdgeMeshFiltering
  DESCRIPTION
    "${DOCUMENTATION}"
  EXCLUDE_FROM_DEFAULT
)
