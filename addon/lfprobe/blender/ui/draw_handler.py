"""A draw callback of the 3D viewport that the add-on adds on register and removes on unregister
(the coverage overlay and the scan point display each keep one)."""

import bpy


class ViewportDrawHandler:
    """One POST_VIEW draw callback of SpaceView3D, added at most once."""

    def __init__(self, draw):
        self._draw = draw
        self._handle = None

    @property
    def active(self) -> bool:
        return self._handle is not None

    def add(self) -> None:
        self._handle = bpy.types.SpaceView3D.draw_handler_add(self._draw, (), "WINDOW", "POST_VIEW")

    def remove(self) -> None:
        if self._handle is not None:
            bpy.types.SpaceView3D.draw_handler_remove(self._handle, "WINDOW")
            self._handle = None
