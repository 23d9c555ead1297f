# The experiment code that both the tool and the Python module run (implicit.mcl.run and friends
# give the numbers of `implicit mcl --json`), with the paper's table aggregation (slit_table.cpp,
# Table 2). Compiled once, position-independent so the module can link it too;
# -fno-semantic-interposition keeps the inlining an executable would get. The apps tests and
# bench_control link it as well; a target that links it also needs a transport (apps/transport/).
set(IMPLICIT_EXPERIMENT_SOURCES
    exp_mcl.cpp exp_mcl_global.cpp exp_slam.cpp exp_slit.cpp slit_table.cpp exp_arm.cpp
    exp_himmelblau.cpp parallel_runs.cpp run_record.cpp context.cpp vehicle.cpp)
list(TRANSFORM IMPLICIT_EXPERIMENT_SOURCES PREPEND ${PROJECT_SOURCE_DIR}/apps/)
find_package(CLI11 REQUIRED)
find_package(nlohmann_json REQUIRED)
add_library(implicit_experiment_objects OBJECT ${IMPLICIT_EXPERIMENT_SOURCES})
set_target_properties(implicit_experiment_objects PROPERTIES POSITION_INDEPENDENT_CODE ON)
target_compile_options(implicit_experiment_objects PRIVATE -fno-semantic-interposition)
target_include_directories(implicit_experiment_objects PUBLIC ${PROJECT_SOURCE_DIR}/apps)
target_link_libraries(implicit_experiment_objects PUBLIC implicit::implicit CLI11::CLI11
                      nlohmann_json::nlohmann_json PRIVATE implicit_warnings)
