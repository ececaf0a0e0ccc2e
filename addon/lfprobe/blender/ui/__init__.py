"""What the add-on shows: the Object and Render panels, and the viewport drawing of probe
grids (coverage overlay) and scan clouds."""
