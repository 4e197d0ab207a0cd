# The .vxlz package's codecs for the web viewer: Draco (positions) and zlib (tables), built for WebAssembly
# from Debian's own sources of the versions the native build links (Debian 12: draco 1.5.5, zlib 1.2.13).
# Emscripten has no Draco, and its zlib port is fetched from the network at build time; Debian's source
# archive (the package registry that apt-get uses) is where the native libraries come from, so the web
# viewer decodes a package with the same code as voxview. Each archive is checked against the SHA-256 that
# Debian's .dsc states, downloaded once into VOXLINES_WEB_DOWNLOADS (put the archives there by hand to build
# offline).
#
# Only what decoding a package needs is compiled: Draco's sequential point-cloud decoder (the package's only
# encoding, spec §5.3) with its attribute decoders and entropy coders; zlib's inflate and deflate (the
# package's streams code links both, the web viewer calls only inflate).
set(VOXLINES_WEB_DOWNLOADS ${PROJECT_BINARY_DIR}/downloads CACHE PATH
    "Where the web build keeps Debian's source archives of Draco and zlib")
set(debian_pool http://deb.debian.org/debian/pool/main)

# Downloads `archive` from Debian's pool (unless a copy with `sha256` is in VOXLINES_WEB_DOWNLOADS) and extracts
# the files matching `patterns` into <build>/<name>; sets `<name>_root` to the archive's top folder there.
function(debian_source name url_path archive sha256 top)
  set(file ${VOXLINES_WEB_DOWNLOADS}/${archive})
  if(EXISTS ${file})
    file(SHA256 ${file} have)
  endif()
  if(NOT have STREQUAL sha256)
    message(STATUS "Downloading ${debian_pool}/${url_path}/${archive}")
    file(DOWNLOAD ${debian_pool}/${url_path}/${archive} ${file} EXPECTED_HASH SHA256=${sha256} STATUS status)
    list(GET status 0 code)
    if(NOT code EQUAL 0)
      file(REMOVE ${file})
      list(GET status 1 why)
      message(FATAL_ERROR "the web viewer's .vxlz decoding needs Debian's source archive ${archive} (${why}): "
                          "put it in ${VOXLINES_WEB_DOWNLOADS} (from ${debian_pool}/${url_path}/), "
                          "or configure with -DVOXLINES_WEB=OFF")
    endif()
  endif()
  set(into ${PROJECT_BINARY_DIR}/${name})
  if(NOT EXISTS ${into}/${sha256})
    file(REMOVE_RECURSE ${into})
    file(ARCHIVE_EXTRACT INPUT ${file} DESTINATION ${into} PATTERNS ${ARGN})
    file(TOUCH ${into}/${sha256})
  endif()
  set(${name}_root ${into}/${top} PARENT_SCOPE)
endfunction()

debian_source(zlib z/zlib zlib_1.2.13.dfsg.orig.tar.bz2
              71feb7947e3c00ef125f83b79a4e529bde31171e5babe48b391f06758d1ab0a1 zlib-1.2.13.dfsg
              "zlib-1.2.13.dfsg/*.c" "zlib-1.2.13.dfsg/*.h")
add_library(web_zlib STATIC)
foreach(source adler32 compress crc32 deflate inffast inflate inftrees trees uncompr zutil)
  target_sources(web_zlib PRIVATE ${zlib_root}/${source}.c)
endforeach()
target_include_directories(web_zlib SYSTEM PUBLIC ${zlib_root})

debian_source(draco d/draco draco_1.5.5+dfsg.orig.tar.xz
              0d4ff5b218a2f9d836c6f44202918402591407b5f59a5103ec288c5600ab087f google-draco-a5b3157
              "google-draco-a5b3157/src/draco/*")
set(draco_src ${draco_root}/src/draco)
# Draco's build generates this header from its options: point clouds only.
file(WRITE ${PROJECT_BINARY_DIR}/draco-features/draco/draco_features.h
     "#ifndef DRACO_FEATURES_H_\n#define DRACO_FEATURES_H_\n#define DRACO_POINT_CLOUD_COMPRESSION_SUPPORTED\n#endif\n")
add_library(web_draco STATIC)
foreach(source
        attributes/attribute_octahedron_transform attributes/attribute_quantization_transform
        attributes/attribute_transform attributes/geometry_attribute attributes/point_attribute
        compression/attributes/attributes_decoder compression/attributes/sequential_attribute_decoder
        compression/attributes/sequential_attribute_decoders_controller
        compression/attributes/sequential_integer_attribute_decoder
        compression/attributes/sequential_normal_attribute_decoder
        compression/attributes/sequential_quantization_attribute_decoder
        compression/bit_coders/adaptive_rans_bit_decoder compression/bit_coders/direct_bit_decoder
        compression/bit_coders/rans_bit_decoder compression/bit_coders/symbol_bit_decoder
        compression/entropy/symbol_decoding
        compression/point_cloud/point_cloud_decoder compression/point_cloud/point_cloud_sequential_decoder
        core/bit_utils core/bounding_box core/data_buffer core/decoder_buffer core/divide core/draco_types
        core/hash_utils core/options core/quantization_utils core/status
        metadata/geometry_metadata metadata/metadata metadata/metadata_decoder
        point_cloud/point_cloud)
  target_sources(web_draco PRIVATE ${draco_src}/${source}.cc)
endforeach()
target_include_directories(web_draco SYSTEM PUBLIC ${draco_root}/src ${PROJECT_BINARY_DIR}/draco-features)
# Draco's own code, not ours: its warnings are not ours to fix.
target_compile_options(web_draco PRIVATE -w)
set_target_properties(web_draco PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE 16)
