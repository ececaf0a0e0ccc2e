"""The bpy-free core of lfprobe: importing scans, baking probe sets, the command line."""
