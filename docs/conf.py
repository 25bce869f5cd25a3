"""Sphinx configuration of the signorini user guide (docs/*.md, MyST Markdown).

The gallery's notebooks (docs/gallery/*.md, MyST notebooks) are executed at every build
by myst-nb through nbclient; a cell that raises fails the build.
"""

project = "signorini"
author = "the signorini developers"
copyright = "2026, the signorini developers"

extensions = ["myst_nb"]
# GitHub-style anchors for every heading down to ####, so `file.md#anchor` links resolve
# here and on GitHub alike.
myst_heading_anchors = 4

# execute every notebook at every build; a failing cell fails the build
nb_execution_mode = "force"
nb_execution_raise_on_error = True
nb_execution_timeout = 600
nb_execution_show_tb = True

exclude_patterns = ["_build", "requirements.txt", "run_commands.py", "gallery/out"]
html_theme = "alabaster"
html_title = "signorini user guide"
