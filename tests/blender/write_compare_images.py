"""Renders Blender's default scene with Cycles at a small size and saves the one render the
ways users hand it to `./lfprobe compare`: plain EXR (RGB and RGBA, float and half, codecs NONE,
ZIP, ZIPS, RLE and PIZ), a multilayer EXR (ViewLayer.Combined plus Depth), PNG 8- and 16-bit
and JPEG, all with the Standard view transform and no dither, so that the PNG is the EXR's
colour sRGB-encoded. Used by tests/python/test_compare_images.py:

    blender -b --factory-startup --python-exit-code 1 -P write_compare_images.py -- OUT_DIR W H
"""

import os
import sys

import bpy

out, width, height = sys.argv[sys.argv.index("--") + 1:][:3]
scene = bpy.context.scene
scene.render.engine = "CYCLES"
scene.cycles.samples = 4
scene.cycles.use_denoising = False
scene.cycles.device = "CPU"
scene.render.resolution_x, scene.render.resolution_y = int(width), int(height)
scene.render.resolution_percentage = 100
scene.render.film_transparent = True
scene.render.dither_intensity = 0.0
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_layers[0].use_pass_z = True
bpy.ops.render.render()
result = bpy.data.images["Render Result"]
settings = scene.render.image_settings

saves = [
    ("rgb_none.exr", "OPEN_EXR", "RGB", "32", "NONE"),
    ("rgb_zip.exr", "OPEN_EXR", "RGB", "32", "ZIP"),
    ("rgba_zips_half.exr", "OPEN_EXR", "RGBA", "16", "ZIPS"),
    ("rgba_rle.exr", "OPEN_EXR", "RGBA", "32", "RLE"),
    ("rgb_piz.exr", "OPEN_EXR", "RGB", "32", "PIZ"),
    ("multilayer.exr", "OPEN_EXR_MULTILAYER", "RGBA", "32", "ZIP"),
    ("multilayer_none.exr", "OPEN_EXR_MULTILAYER", "RGBA", "32", "NONE"),
    ("rgb8.png", "PNG", "RGB", "8", None),
    ("rgba16.png", "PNG", "RGBA", "16", None),
    ("rgb.jpg", "JPEG", "RGB", None, None),
]
for name, file_format, mode, depth, codec in saves:
    settings.file_format = file_format
    settings.color_mode = mode
    if depth is not None:
        settings.color_depth = depth
    if codec is not None:
        settings.exr_codec = codec
    if file_format == "JPEG":
        settings.quality = 95
    result.save_render(os.path.join(out, name), scene=scene)
