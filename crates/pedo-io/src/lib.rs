//! Plantar-pressure recordings in; contours, brightness surfaces and isobaric contours out.
