"""Finding an object of one type by name in a scene, for the operators and batch commands that
take object names (the views to serve, a render camera, reference meshes)."""


def _single_quoted(text: str) -> str:
    return f"'{text}'"


def object_of_type(scene, name: str, obj_type: str, error_type, quote=_single_quoted):
    """The object called name in scene; error_type(message) when there is none or it is not an
    obj_type (e.g. "CAMERA"). quote writes the names into the message."""
    obj = scene.objects.get(name)
    if obj is None:
        raise error_type(f"no object named {quote(name)} in scene {quote(scene.name)}")
    if obj.type != obj_type:
        raise error_type(f"object {quote(name)} is a {obj.type.lower()}, not a {obj_type.lower()}")
    return obj
