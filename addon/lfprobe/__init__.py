"""lfprobe: light field probes from laser scans of interiors.

The package has two layers: ``lfprobe.core`` (the pipeline, the command line, reports),
which imports without Blender, and the Blender add-on's UI modules. The native core is the
extension module ``lfprobe._native``, built by ``tools/setup.sh``.
"""
