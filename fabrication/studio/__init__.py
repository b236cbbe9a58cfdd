"""``ppfab studio``: design P and PP gridshells interactively in the browser (layer 3, beside the command line).

:mod:`.model` holds the design being edited, its closed-form re-solve and the PP check, free of any user
interface; :mod:`.handles` maps the designer's handles to construction parameters; :mod:`.figures` computes the
live fabrication figures; :mod:`.app` is the browser interface (viser, imported only when the studio starts);
:mod:`.jobs` runs builds in the background; :mod:`.guard` answers only requests for the studio's own address
that carry the session key; :mod:`.saving` keeps Save from overwriting the design read or a file the studio did
not write.
"""
