# The reproduction report (apps/report*.cpp): compiled once, for the tool and for the apps tests,
# which test its number formatting, agreement test, numbers and text files directly.
if(NOT TARGET implicit_report_objects)
  file(GLOB IMPLICIT_REPORT_SOURCES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/apps/report*.cpp)
  find_package(nlohmann_json REQUIRED)
  add_library(implicit_report_objects OBJECT ${IMPLICIT_REPORT_SOURCES})
  target_include_directories(implicit_report_objects PUBLIC ${PROJECT_SOURCE_DIR}/apps
                             ${PROJECT_SOURCE_DIR})
  target_link_libraries(implicit_report_objects PUBLIC implicit::implicit
                        nlohmann_json::nlohmann_json PRIVATE implicit_warnings)
endif()
