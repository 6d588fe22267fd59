# The layers of src/viosfm/, lowest first: a layer's code includes and links
# only layers listed before it (and itself). The one list of the order:
# src/viosfm/CMakeLists.txt adds the layers in it, viosfm_add_layer refuses a
# link to a higher layer, and cmake/CheckLayers.cmake (the ctest
# `layers/include_order`) refuses an include of a higher layer.
#
#   util        errors, logging, files, hashes, time stamps, threads
#   geometry    rigid and similarity transforms, epipolar geometry, pose blocks
#   sensor      camera models, IMU samples and noise, the sensor rig
#   scene       data models: sequence, trajectory, features, reconstruction,
#               two-view geometry, the VIO uncertainty model
#   io          every file format read or written
#   features    SIFT extraction
#   estimators  minimal solvers and RANSAC
#   vio         viosfm's own visual-inertial odometry
#   retrieval   vocabulary tree image retrieval
#   matching    pairs, matching, VIO-aided verification
#   ba          bundle adjustment with relative-pose priors
#   sfm         batched incremental mapping, registration, metric scale
#   eval        trajectory evaluation (independent of what it judges)
#   report      HTML report
#   sim         the simulator (tests of any layer may use it as a fixture)
#   pipeline    `viosfm run`: the stages and their driver
#   cli         the command line
set(VIOSFM_LAYERS
  util geometry sensor scene io features estimators vio retrieval matching ba sfm eval report sim
  pipeline cli)
