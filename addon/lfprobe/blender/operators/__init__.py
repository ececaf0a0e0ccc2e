"""The add-on's operators: import scans, add and fit probe grids, bake, add probes for views,
compare with a ground truth; job_modal.py runs their native jobs without blocking the UI."""
