"""The Blender side of lfprobe: everything here imports bpy. It gathers inputs (scan
objects, probe grids, cameras) for lfprobe.core and the native module, and shows outputs;
it holds no algorithm of its own. lfprobe/__init__.py registers the modules in order."""
