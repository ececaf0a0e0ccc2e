"""Registering operator classes together with the menu entry that offers them: the entry is
appended after the classes and removed before them, so a menu never draws an unregistered
operator."""

import bpy


def classes_with_menu_entry(classes, menu_name: str, draw_entry):
    """(register, unregister) for the classes and draw_entry appended to bpy.types.<menu_name>."""
    register_classes, unregister_classes = bpy.utils.register_classes_factory(tuple(classes))

    def register():
        register_classes()
        getattr(bpy.types, menu_name).append(draw_entry)

    def unregister():
        getattr(bpy.types, menu_name).remove(draw_entry)
        unregister_classes()

    return register, unregister
