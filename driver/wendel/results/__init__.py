"""What a run leaves behind: VTU/PVD (:mod:`.vtu`), pictures (:mod:`.pictures`), provenance, histories and
summary.json (:mod:`.summary`), mesh studies (:mod:`.study`) and other codes' figures (:mod:`.comparisons`)."""
