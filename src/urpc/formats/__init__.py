"""The input file formats, each declared once as a typed schema (pydantic).

One module per format: :mod:`.uncertainty` (uncertainty box), :mod:`.parameter_point` (a true
plant), :mod:`.scenario`, :mod:`.module` and :mod:`.assembly` (modular arms). The value grammar
(numbers as arithmetic, vectors, interval notations) is in :mod:`.values`, and :mod:`.base` turns
validation errors into :class:`urpc.errors.InputError` naming the file and the field. The JSON
Schemas in ``docs/schemas/`` are generated from these models (:func:`json_schemas`).

This layer depends only on :mod:`urpc.errors` and :mod:`urpc.expressions`: the robot model, the
controllers and the studies build on it, never the other way around.
"""
