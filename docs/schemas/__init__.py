"""The JSON Schemas of the file formats, installed as the data package ``urpc._schemas``."""
