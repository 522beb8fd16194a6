"""The switching study: walks and telegraphs made with numpy (:mod:`.paths`) scored by the
detector's two-level and walk fits (:mod:`.score`)."""
