"""The Blender side of lfprobe: everything here imports bpy. It gathers inputs (scan
objects, probe grids, cameras) for lfprobe.core and the native module, and shows outputs;
it holds no algorithm of its own. lfprobe/__init__.py registers the modules in order.

Laid out as BlendLuxCore lays out an add-on: engine/ (the render engine and the viewport's
progressive refinement), properties/ (PropertyGroups), ui/ (panels, viewport drawing) and
operators/ (bake, import, grid, place views, compare, the modal job runner); the gatherers
they share (grid.py, probe_view.py, camera_export.py, mesh_export.py, scan_object.py,
scene_objects.py) stay here."""
