"""Studies of the article: :mod:`.hsi`, the human-structure interaction study of Section 6 (Table 3-4)."""
