# All third-party dependencies come from Debian 12 packages; scripts/deps.sh
# installs them. Finding them in one place keeps module CMakeLists short.
find_package(PkgConfig REQUIRED)
find_package(Threads REQUIRED)
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(yaml-cpp REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(CLI11 REQUIRED)
find_package(NLopt REQUIRED)
pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)
pkg_check_modules(HIDAPI REQUIRED IMPORTED_TARGET hidapi-hidraw)
pkg_check_modules(LIBUSB REQUIRED IMPORTED_TARGET libusb-1.0)
# Message authentication on the LCM link (bridge/link_auth.hpp): HMAC-SHA-512-256.
pkg_check_modules(SODIUM REQUIRED IMPORTED_TARGET libsodium)
find_program(LCM_GEN lcm-gen REQUIRED)
if(TSMH_BUILD_TESTS)
  find_package(GTest REQUIRED)
  find_package(benchmark REQUIRED)
endif()
