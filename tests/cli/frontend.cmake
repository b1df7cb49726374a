# Command-line tests of cge_frontend (included by CMakeLists.txt when the tool is built). The
# fixtures under frontend/ are hand-made (frontend/README.md derives the values checked here). The
# JSON is printed with one key per line, so each STDOUT regex matches one "key": value line.
# Files the tests write go to this directory's build folder, never to the source tree.

set(fe_out ${CMAKE_CURRENT_BINARY_DIR})
set(fe_masks ARGS --rgb frontend/rgb.png --depth frontend/depth.png --masks frontend/masks/frame.png)

# The JSON report with the hand-made mask folder.
cge_cli_test(frontend_masks PROGRAM cge_frontend ${fe_masks}
  STDOUT [[ *"tool": "cge_frontend",]] [[ *"width_px": 160,]] [[ *"height_px": 120,]]
         [[ *"source": "masks",]] [[ *"instances_csv": "frontend/masks/instances.csv",]]
         [[ *"seed": 0,]] [[ *"mad_scale": 1\.0,]]
         # the person: box = the whole rectangle, mask = rectangle minus the notch
         [[ *"class_name": "person",]] [[ *"dynamic": true,]] [[ *"x_min": 48\.0,]] [[ *"y_min": 24\.0,]]
         [[ *"width": 32\.0,]] [[ *"height": 72\.0]] [[ *"mask_area_px": 1968,]]
         [[ *"samples_drawn": 100,]] [[ *"valid_samples": [1-9][0-9]*,]] [[ *"samples_invalid_depth": 0,]]
         [[ *"mean_depth_m": (1\.9[0-9]*|2\.0[0-9]*|2\.1),]] [[ *"mad_m": (0\.0[0-9]*[1-9][0-9]*|0\.1),]]
         [[ *"mad_test_applied": true,]] [[ *"mad_skipped": null]]
         # the chair: not a dynamic class
         [[ *"class_name": "chair",]] [[ *"dynamic": false,]] [[ *"mask_area_px": 900,]] [[ *"mad": null]]
         # the eight corners in the notch are caught by the depth test, features in the mask by the mask
         [[ *"detected": [1-9][0-9]*,]] [[ *"static": [1-9][0-9]*,]] [[ *"dynamic_by_mask": [1-9][0-9]*,]]
         [[ *"dynamic_by_mad": 8]]
         [[ *"load": [0-9.]+,]] [[ *"orb": [0-9.]+,]] [[ *"segmentation": [0-9.]+,]] [[ *"filter": [0-9.]+,]]
         [[ *"total": [0-9.]+]]
  STDOUT_NOT [[.*"out_image".*]] [[.*NaN.*]])

# k = 0 flags nothing by MAD (the test is strict: Dev < 0 never holds).
cge_cli_test(frontend_mad_scale_zero PROGRAM cge_frontend ${fe_masks} --mad-scale 0 --seed 7
  STDOUT [[ *"seed": 7,]] [[ *"mad_scale": 0\.0,]] [[ *"dynamic_by_mad": 0]] [[ *"dynamic_by_mask": [1-9][0-9]*,]])

# The chair as the dynamic class: its depth is 3.0 m everywhere, so mean 3, MAD 0, nothing by MAD.
cge_cli_test(frontend_dynamic_chair PROGRAM cge_frontend ${fe_masks} --dynamic-classes chair
  STDOUT [[ *"chair"]] [[ *"mean_depth_m": 3\.0,]] [[ *"mad_m": 0\.0,]] [[ *"mad": null]] [[ *"dynamic_by_mad": 0]]
  STDOUT_NOT [[ *"person"]])
cge_cli_test(frontend_dynamic_two PROGRAM cge_frontend ${fe_masks} --dynamic-classes person,chair
  STDOUT [[ *"person",]] [[ *"chair"]] [[ *"mean_depth_m": 3\.0,]] [[ *"dynamic_by_mad": 8]]
  STDOUT_NOT [[ *"mad": null,?]])

# Neither --model nor --masks: no instances, and the output says so.
cge_cli_test(frontend_no_segmentation PROGRAM cge_frontend ARGS --rgb frontend/rgb.png --depth frontend/depth.png
  STDOUT [[ *"source": "none",]] [[ *"note": "neither --model nor --masks was given: no instances.*",]]
         [[ *"instances": ..,]] [[ *"dynamic_by_mask": 0,]] [[ *"dynamic_by_mad": 0]] [[ *"static": [1-9][0-9]*,]])
cge_cli_test(frontend_features PROGRAM cge_frontend ARGS --rgb frontend/rgb.png --depth frontend/depth.png
                                                       --features 5
  STDOUT [[ *"detected": [1-5],]])

# Bad flags.
cge_cli_test(frontend_no_rgb EXIT 2 PROGRAM cge_frontend ARGS --depth frontend/depth.png STDERR "--rgb is required")
cge_cli_test(frontend_unknown_flag EXIT 2 PROGRAM cge_frontend ${fe_masks} --frobnicate STDERR "frobnicate")
cge_cli_test(frontend_model_and_masks EXIT 2 PROGRAM cge_frontend ${fe_masks} --model frontend/rgb.png
  STDERR "--model excludes --masks|--masks excludes --model")
cge_cli_test(frontend_features_zero EXIT 2 PROGRAM cge_frontend ${fe_masks} --features 0
  STDERR "--features must be at least 1")
cge_cli_test(frontend_features_text EXIT 2 PROGRAM cge_frontend ${fe_masks} --features many STDERR "--features")
cge_cli_test(frontend_mad_scale_negative EXIT 2 PROGRAM cge_frontend ${fe_masks} --mad-scale -1
  STDERR "--mad-scale must be a finite number >= 0")
cge_cli_test(frontend_depth_scale_zero EXIT 2 PROGRAM cge_frontend ${fe_masks} --depth-scale 0
  STDERR "--depth-scale must be a finite number > 0")
cge_cli_test(frontend_seed_negative EXIT 2 PROGRAM cge_frontend ${fe_masks} --seed -3 STDERR "--seed: must not be negative")
cge_cli_test(frontend_bad_class EXIT 2 PROGRAM cge_frontend ${fe_masks} --dynamic-classes person,persn
  STDERR "--dynamic-classes: 'persn' is not a COCO class name")
cge_cli_test(frontend_threshold_needs_model EXIT 2 PROGRAM cge_frontend ${fe_masks} --mask-threshold 0.4
  STDERR "--mask-threshold requires --model")
cge_cli_test(frontend_bad_depth_estimate EXIT 2 PROGRAM cge_frontend ${fe_masks} --depth-estimate everything
  STDERR "--depth-estimate")
cge_cli_test(frontend_bad_decoding EXIT 2 PROGRAM cge_frontend ARGS --rgb frontend/rgb.png --depth frontend/depth.png
                                                          --model frontend/rgb.png --mask-decoding best
  STDERR "--mask-decoding")
cge_cli_test(frontend_force_needs_out_image EXIT 2 PROGRAM cge_frontend ${fe_masks} --force
  STDERR "--force requires --out-image")

# Files that are missing, unreadable or of the wrong kind: the message names the flag and the file.
cge_cli_test(frontend_missing_rgb EXIT 2 PROGRAM cge_frontend ARGS --rgb frontend/none.png --depth frontend/depth.png
  STDERR "--rgb: file 'frontend/none\\.png' does not exist")
cge_cli_test(frontend_missing_depth EXIT 2 PROGRAM cge_frontend ARGS --rgb frontend/rgb.png --depth frontend/none.png
  STDERR "--depth: file 'frontend/none\\.png' does not exist")
cge_cli_test(frontend_rgb_directory EXIT 2 PROGRAM cge_frontend ARGS --rgb frontend --depth frontend/depth.png
  STDERR "--rgb: 'frontend' is a directory")
cge_cli_test(frontend_rgb_not_image EXIT 2 PROGRAM cge_frontend
  ARGS --rgb frontend/not_an_image.png --depth frontend/depth.png
  STDERR "--rgb: cannot read 'frontend/not_an_image\\.png' as an image")
cge_cli_test(frontend_size_mismatch EXIT 2 PROGRAM cge_frontend ARGS --rgb frontend/rgb.png --depth frontend/depth_small.png
  STDERR "--depth: 'frontend/depth_small\\.png' is 80 x 60 pixels but --rgb 'frontend/rgb\\.png' is 160 x 120")
cge_cli_test(frontend_depth_type EXIT 2 PROGRAM cge_frontend ARGS --rgb frontend/rgb.png --depth frontend/depth_8bit.png
  STDERR "--depth: 'frontend/depth_8bit\\.png' is CV_8UC1, expected a single-channel 16-bit image")
cge_cli_test(frontend_missing_masks EXIT 2 PROGRAM cge_frontend
  ARGS --rgb frontend/rgb.png --depth frontend/depth.png --masks frontend/masks/none.png
  STDERR "--masks: file 'frontend/masks/none\\.png' does not exist")
cge_cli_test(frontend_masks_size EXIT 2 PROGRAM cge_frontend
  ARGS --rgb frontend/rgb.png --depth frontend/depth.png --masks frontend/masks/small.png
  STDERR "frontend/masks/small\\.png")
cge_cli_test(frontend_masks_no_csv EXIT 2 PROGRAM cge_frontend
  ARGS --rgb frontend/rgb.png --depth frontend/depth.png --masks frontend/nocsv/frame.png
  STDERR "frontend/nocsv/instances\\.csv")
cge_cli_test(frontend_masks_not_png EXIT 2 PROGRAM cge_frontend
  ARGS --rgb frontend/rgb.png --depth frontend/depth.png --masks frontend/masks/instances.csv
  STDERR "--masks: 'frontend/masks/instances\\.csv' is not a \\.png file")
cge_cli_test(frontend_missing_model EXIT 2 PROGRAM cge_frontend
  ARGS --rgb frontend/rgb.png --depth frontend/depth.png --model frontend/none.onnx
  STDERR "--model: file 'frontend/none\\.onnx' does not exist")
# A file that is not a YOLOv8-seg model: the segmenter's message is passed through.
cge_cli_test(frontend_model_not_onnx EXIT 2 PROGRAM cge_frontend
  ARGS --rgb frontend/rgb.png --depth frontend/depth.png --model p5.txt
  STDERR "Yolov8Segmenter: p5\\.txt.*is not an ONNX model")

# --out-image never replaces a file without --force. A copy of rgb.png stands for the user's file:
# refused (exit 2, nothing on stdout), left as it was, then replaced with --force.
add_test(NAME cli.frontend_out_image_setup
         COMMAND ${CMAKE_COMMAND} -E copy ${CMAKE_CURRENT_SOURCE_DIR}/frontend/rgb.png ${fe_out}/frontend_existing.png)
cge_cli_test(frontend_out_image_refused EXIT 2 PROGRAM cge_frontend ${fe_masks} --out-image ${fe_out}/frontend_existing.png
  STDERR "--out-image: '.*frontend_existing\\.png' exists; refusing to overwrite it \\(add --force")
add_test(NAME cli.frontend_out_image_untouched
         COMMAND ${CMAKE_COMMAND} -E compare_files ${CMAKE_CURRENT_SOURCE_DIR}/frontend/rgb.png
                 ${fe_out}/frontend_existing.png)
cge_cli_test(frontend_out_image_force PROGRAM cge_frontend ${fe_masks} --out-image ${fe_out}/frontend_existing.png --force
  STDOUT [[ *"out_image": ".*frontend_existing\.png"]])
set_tests_properties(cli.frontend_out_image_setup PROPERTIES FIXTURES_SETUP cge_frontend_existing)
set_tests_properties(cli.frontend_out_image_refused PROPERTIES FIXTURES_REQUIRED cge_frontend_existing)
set_tests_properties(cli.frontend_out_image_untouched PROPERTIES FIXTURES_REQUIRED cge_frontend_existing
                                                                DEPENDS cli.frontend_out_image_refused)
set_tests_properties(cli.frontend_out_image_force PROPERTIES FIXTURES_REQUIRED cge_frontend_existing
                                                             DEPENDS cli.frontend_out_image_untouched)

# A new file is written without --force; it is an image of the frame's size (it serves as --rgb).
add_test(NAME cli.frontend_out_image_new_setup COMMAND ${CMAKE_COMMAND} -E rm -f ${fe_out}/frontend_new.png)
cge_cli_test(frontend_out_image_new PROGRAM cge_frontend ${fe_masks} --out-image ${fe_out}/frontend_new.png
  STDOUT [[ *"out_image": ".*frontend_new\.png"]])
cge_cli_test(frontend_out_image_readable PROGRAM cge_frontend
  ARGS --rgb ${fe_out}/frontend_new.png --depth frontend/depth.png STDOUT [[ *"width_px": 160,]])
set_tests_properties(cli.frontend_out_image_new_setup PROPERTIES FIXTURES_SETUP cge_frontend_new)
set_tests_properties(cli.frontend_out_image_new PROPERTIES FIXTURES_REQUIRED cge_frontend_new)
set_tests_properties(cli.frontend_out_image_readable PROPERTIES FIXTURES_REQUIRED cge_frontend_new
                                                               DEPENDS cli.frontend_out_image_new)
cge_cli_test(frontend_out_image_extension EXIT 2 PROGRAM cge_frontend ${fe_masks} --out-image ${fe_out}/picture.xyz
  STDERR "--out-image: OpenCV cannot write an image named")

# --help and --version.
cge_cli_test(frontend_too_many_features EXIT 2 PROGRAM cge_frontend MEMORY_KB 2000000 ${fe_masks} --features 2000000000
  STDERR "--features must be at most 100000")
# A truncated PNG: the tool's own error comes first, libpng's complaint only inside it.
cge_cli_test(frontend_broken_png EXIT 2 PROGRAM cge_frontend ARGS --rgb frontend/broken.png --depth frontend/depth.png
  STDERR "^cge_frontend: error: --rgb: cannot read 'frontend/broken\\.png' as an image")
cge_cli_test(frontend_help PROGRAM cge_frontend ARGS --help STDOUT ".*Usage:.*" ".*--rgb.*" ".*--out-image.*")
string(REPLACE "." "\\." fe_version_regex "${PROJECT_VERSION}")
cge_cli_test(frontend_version PROGRAM cge_frontend ARGS --version STDOUT "cge_frontend ${fe_version_regex}")

# The real frame and model of ../shared (checked when this build was configured): skipped, and
# reported by ctest as skipped, when they are absent.
set(fe_tum ${PROJECT_SOURCE_DIR}/../shared/data/tum_fr3_walking_xyz)
set(fe_model ${PROJECT_SOURCE_DIR}/../shared/models/yolov8n-seg-640.onnx)
set(fe_rgb ${fe_tum}/rgb/1341846313.592026.png)
set(fe_depth ${fe_tum}/depth/1341846313.592088.png)
if(EXISTS ${fe_model} AND EXISTS ${fe_rgb} AND EXISTS ${fe_depth})
  # Both people are dynamic instances with a MAD test; the picture is left in the build folder.
  cge_cli_test(frontend_tum_yolov8 PROGRAM cge_frontend
    ARGS --rgb ${fe_rgb} --depth ${fe_depth} --model ${fe_model} --out-image ${fe_out}/frontend_tum.png --force
    STDOUT [[ *"source": "yolov8",]] [[ *"input_size": .]] [[ *"class_name": "person",]] [[ *"dynamic": true,]]
           [[ *"mad_test_applied": true,]] [[ *"dynamic_by_mask": [1-9][0-9]*,]] [[ *"detected": 1000,]]
           [[ *"out_image": ".*frontend_tum\.png"]]
    STDOUT_NOT [[ *"mad_test_applied": false,]])
  cge_cli_test(frontend_tum_retina PROGRAM cge_frontend
    ARGS --rgb ${fe_rgb} --depth ${fe_depth} --model ${fe_model} --mask-decoding retina --mask-threshold 0.5
    STDOUT [[ *"mask_decoding": "retina",]] [[ *"class_name": "person",]])
  # The frame with almost no depth on the people: the report says why the MAD test was skipped.
  set(fe_no_depth ARGS --rgb ${fe_tum}/rgb/1341846316.570121.png --depth ${fe_tum}/depth/1341846316.570146.png
                       --model ${fe_model})
  cge_cli_test(frontend_tum_mad_skipped PROGRAM cge_frontend ${fe_no_depth}
    STDOUT [[ *"depth_estimate": "box_samples"]] [[ *"mad_test_applied": false,]] [[ *"mad_skipped": {]]
           [[ *"reason": "too_few_valid_samples",]] [[ *"valid_samples": [0-4],]] [[ *"min_valid_samples": 5]]
           [[ *"dynamic_by_mad": 0]]
    STDOUT_NOT [[ *"mad_test_applied": true,]])
  cge_cli_test(frontend_tum_mask_pixels_skipped PROGRAM cge_frontend ${fe_no_depth} --depth-estimate mask_pixels
    STDOUT [[ *"depth_estimate": "mask_pixels",]] [[ *"min_valid_mask_fraction": 0\.5]]
           [[ *"reason": "too_little_depth_in_mask",]] [[ *"valid_fraction": 0\.0[0-9]*,]]
           [[ *"min_valid_mask_fraction": 0\.5]] [[ *"dynamic_by_mad": 0]]
    STDOUT_NOT [[ *"mad_test_applied": true,]])
else()
  foreach(fe_name frontend_tum_yolov8 frontend_tum_retina frontend_tum_mad_skipped frontend_tum_mask_pixels_skipped)
    add_test(NAME cli.${fe_name} COMMAND ${CMAKE_COMMAND} -E echo
             "skipped: ${fe_model} or the TUM frame ${fe_rgb} is absent")
    set_tests_properties(cli.${fe_name} PROPERTIES SKIP_REGULAR_EXPRESSION "skipped: ")
  endforeach()
endif()
