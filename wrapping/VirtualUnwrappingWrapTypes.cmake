# The mesh types the module is wrapped for, as ITK's own wrapping names them
# (itk::Mesh<T, D> with default traits is "M<T><D>", itk::QuadEdgeMesh<double, D> is
# "QEMD<D>"). Read by wrapping/CMakeLists.txt and by the wrapping check
# (cmake/VirtualUnwrappingWrapCheck.cmake).
foreach(_vu_dim 2 3)
  list(FIND ITK_WRAP_IMAGE_DIMS ${_vu_dim} _vu_found)
  if(_vu_found LESS 0)
    message(FATAL_ERROR "VirtualUnwrapping wrapping needs ITK_WRAP_IMAGE_DIMS to contain ${_vu_dim} "
      "(3D volumes and meshes, 2D textures); it is \"${ITK_WRAP_IMAGE_DIMS}\"")
  endif()
endforeach()
if(NOT ITK_WRAP_float OR NOT ITK_WRAP_unsigned_char)
  message(FATAL_ERROR "VirtualUnwrapping wrapping needs ITK_WRAP_float and ITK_WRAP_unsigned_char")
endif()

set(VU_WRAP_MESHES MF3 MD3 QEMD3)
set(VU_WRAP_MESH_MF3 "itk::Mesh< ${ITKT_F},3 >")
set(VU_WRAP_MESH_MD3 "itk::Mesh< ${ITKT_D},3 >")
set(VU_WRAP_MESH_QEMD3 "itk::QuadEdgeMesh< ${ITKT_D},3 >")
