# The module layers of src/: each module and the modules it may include and link (its direct
# dependencies; what they may use is allowed too). docs/architecture.md explains the rule. The top-level
# CMakeLists.txt links each u3d_<module> to exactly these, and cmake/check_layering.cmake fails the
# configure step and the `layering` test when a file includes a module that is not below its own.
# A folder of src/ without a line here is an error, so a new module must take its place first.
set(UNIQUE3D_MODULES core io geometry render nn isomer eval pipeline batch server cli python)
set(UNIQUE3D_LAYER_core "")
set(UNIQUE3D_LAYER_io core)
set(UNIQUE3D_LAYER_geometry core)
set(UNIQUE3D_LAYER_render core geometry)
set(UNIQUE3D_LAYER_nn core)
set(UNIQUE3D_LAYER_isomer core io geometry render)
set(UNIQUE3D_LAYER_eval core io geometry render)
set(UNIQUE3D_LAYER_pipeline core io geometry render nn isomer eval)
set(UNIQUE3D_LAYER_batch core io geometry render nn isomer eval pipeline)
set(UNIQUE3D_LAYER_server core io geometry render nn isomer eval pipeline)
set(UNIQUE3D_LAYER_cli core io geometry render nn isomer eval pipeline batch server)
set(UNIQUE3D_LAYER_python core io geometry render nn isomer eval pipeline)
