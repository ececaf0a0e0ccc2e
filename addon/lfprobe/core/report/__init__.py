"""The error-analysis report (bpy-free): a scene file in, a sweep of probe settings measured
against Embree ground truth, and a self-contained HTML page with JSON and CSV figures out.

Modules: scene (the scene file contract), presets (what each preset sweeps), workspace (files
of one run), sweep (scans, bakes, renders, metrics), peers (splatting and an Open3D Poisson
mesh), stability (the numerical hard cases), plots (matplotlib figures), html (the page),
runner (the whole run, as `./lfprobe report` calls it).
"""
