"""The Motion-Lab tab's pages: one widget per page (``ui/lab_tab.py`` puts them together)."""
