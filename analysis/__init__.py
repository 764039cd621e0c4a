"""Analysis of studyrun study files: `studyfile` reads them, `report`, `figures` and
`diagnosis_figures` draw them, `sensitivity`, `significance`, `features` and `dataset`
analyse them (docs/analysis.md, docs/diagnosis.md, docs/cookbook.md)."""
