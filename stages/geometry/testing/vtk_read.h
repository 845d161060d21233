// Reading a .vtp back with VTK 9's own reader (vtkXMLPolyDataReader), the
// oracle for "ParaView opens it", for the two tests that link VTK
// (io/vtp_test.cc, export/vtp_stages_test.cc). Test-only, header-only: no
// library includes it, so VTK stays out of pointbake.
#pragma once

#include <vtkCommand.h>
#include <vtkFieldData.h>
#include <vtkNew.h>
#include <vtkPolyData.h>
#include <vtkSmartPointer.h>
#include <vtkStringArray.h>
#include <vtkXMLPolyDataReader.h>

#include <string>

namespace pb::testing {

// Counts the errors VTK reports (instead of printing them and going on).
class VtkErrorCounter : public vtkCommand {
 public:
  static VtkErrorCounter* New() { return new VtkErrorCounter; }
  void Execute(vtkObject*, unsigned long, void* data) override {
    ++errors;
    last = data ? static_cast<const char*>(data) : "";
  }
  int errors = 0;
  std::string last;
};

struct VtkRead {
  vtkSmartPointer<vtkPolyData> poly;
  int errors = 0;           // errors VTK's reader reported
  std::string last_error;   // the last of them
};

inline VtkRead ReadVtpWithVtk(const std::string& path) {
  vtkNew<vtkXMLPolyDataReader> reader;
  vtkNew<VtkErrorCounter> counter;
  reader->AddObserver(vtkCommand::ErrorEvent, counter);
  reader->SetFileName(path.c_str());
  reader->Update();
  VtkRead read;
  read.poly = reader->GetOutput();
  read.errors = counter->errors;
  read.last_error = counter->last;
  return read;
}

// A one-value string array of the field data, or "<missing>".
inline std::string VtkFieldString(vtkPolyData* poly, const char* name) {
  auto* array = vtkStringArray::SafeDownCast(poly->GetFieldData()->GetAbstractArray(name));
  return array && array->GetNumberOfValues() == 1 ? array->GetValue(0) : "<missing>";
}

}  // namespace pb::testing
