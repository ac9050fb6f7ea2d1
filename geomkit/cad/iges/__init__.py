"""The IGES reader: file records, entities, faces."""
