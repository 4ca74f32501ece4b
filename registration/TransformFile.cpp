// SPDX-License-Identifier: Apache-2.0
/// @file TransformFile.cpp
/// @brief ITK's transform writer and reader (TxtTransformIO), registered by
/// hand: without ITK's use-file no IO factory is registered, and the writer
/// would throw.

#include "registration/TransformFile.h"

#include "core/Errors.h"

#include <itkAffineTransform.h>
#include <itkMatrixOffsetTransformBase.h>
#include <itkTransformFileReader.h>
#include <itkTransformFileWriter.h>
#include <itkTxtTransformIOFactory.h>

#include <fstream>
#include <mutex>
#include <sstream>
#include <unistd.h>

namespace voxhap::registration {

namespace {

namespace fs = std::filesystem;

void registerTransformIo()
{
    static std::once_flag once;
    std::call_once(once, [] { itk::TxtTransformIOFactory::RegisterOneFactory(); });
}

/// ITK reads and writes named files only: one scratch file at a time.
std::mutex& scratchMutex()
{
    static std::mutex m;
    return m;
}

std::string slurp(const fs::path& file)
{
    std::ifstream in(file, std::ios::binary);
    std::ostringstream os;
    os << in.rdbuf();
    return os.str();
}

/// A scratch file for ITK (under scratchMutex()).
struct ScratchFile {
    ScratchFile()
        : path(fs::temp_directory_path() /
              ("voxhap-transform-" + std::to_string(::getpid()) + "-" + std::to_string(counter()++) + ".tfm"))
    {
    }
    ~ScratchFile()
    {
        std::error_code ec;
        fs::remove(path, ec);
    }
    static int& counter()
    {
        static int n = 0;
        return n;
    }
    fs::path path;
};

} // namespace

std::string itkTransformText(const AffineMap& mrFromCt)
{
    registerTransformIo();
    auto affine = itk::AffineTransform<double, 3>::New();
    itk::Matrix<double, 3, 3> m;
    itk::AffineTransform<double, 3>::OutputVectorType t;
    for (unsigned a = 0; a < 3; ++a) {
        t[a] = mrFromCt.offset[int(a)];
        for (unsigned b = 0; b < 3; ++b) m(a, b) = mrFromCt.linear(int(a), int(b));
    }
    affine->SetMatrix(m);
    affine->SetTranslation(t); // centre (0, 0, 0): the translation is the offset
    std::lock_guard<std::mutex> lock(scratchMutex());
    ScratchFile scratch;
    try {
        auto writer = itk::TransformFileWriterTemplate<double>::New();
        writer->SetInput(affine);
        writer->SetFileName(scratch.path.string());
        writer->Update();
    } catch (const itk::ExceptionObject& e) {
        throw IoError(scratch.path.string() + ": ITK could not write the transform (" + e.GetDescription() + ")");
    }
    return slurp(scratch.path);
}

AffineMap readItkTransform(const fs::path& file)
{
    registerTransformIo();
    auto reader = itk::TransformFileReaderTemplate<double>::New();
    reader->SetFileName(file.string());
    try {
        reader->Update();
    } catch (const itk::ExceptionObject& e) {
        throw IoError(file.string() + ": not an ITK transform file (" + e.GetDescription() + ")");
    }
    const auto* list = reader->GetTransformList();
    if (!list || list->size() != 1) {
        throw IoError(file.string() + ": expected one transform, found " + std::to_string(list ? list->size() : 0));
    }
    using Linear = itk::MatrixOffsetTransformBase<double, 3, 3>;
    const auto* linear = dynamic_cast<const Linear*>(list->front().GetPointer());
    if (!linear) {
        throw IoError(file.string() + ": transform '" + list->front()->GetTransformTypeAsString() +
            "' is not affine (rigid, versor, Euler or affine)");
    }
    AffineMap map;
    for (int a = 0; a < 3; ++a) {
        map.offset[a] = linear->GetOffset()[unsigned(a)];
        for (int b = 0; b < 3; ++b) map.linear(a, b) = linear->GetMatrix()(unsigned(a), unsigned(b));
    }
    return map;
}

AffineMap parseItkTransform(const std::string& text, const std::string& where)
{
    std::lock_guard<std::mutex> lock(scratchMutex());
    ScratchFile scratch;
    {
        std::ofstream out(scratch.path, std::ios::binary);
        out << text;
        if (!out) throw IoError(scratch.path.string() + ": cannot write a scratch copy of " + where);
    }
    try {
        return readItkTransform(scratch.path);
    } catch (const IoError& e) {
        throw IoError(where + ": " + std::string(e.what()).substr(scratch.path.string().size() + 2));
    }
}

} // namespace voxhap::registration
