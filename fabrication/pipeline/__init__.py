"""The build pipeline: a design file → a typed :class:`~fabrication.pipeline.records.Build` → an output folder.

* :mod:`.design` — the design file (TOML) and its sections;
* :mod:`.pipeline` — :func:`~fabrication.pipeline.stages.build`, one function per stage;
* :mod:`.records` — the frozen stage records and :class:`~fabrication.pipeline.records.Build`;
* :mod:`.folder` — atomic output folders and files;
* :mod:`.progress` — the progress display.
"""
