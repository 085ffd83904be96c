"""Built-in robot descriptions shipped with urpc (a data package; see urpc.model.catalog)."""
