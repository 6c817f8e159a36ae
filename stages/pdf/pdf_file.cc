#include "stages/pdf/pdf_file.h"

#include <cstdio>
#include <qpdf/QPDF.hh>
#include <qpdf/QPDFPageDocumentHelper.hh>
#include <qpdf/QPDFPageObjectHelper.hh>
#include <qpdf/QPDFWriter.hh>
#include <qpdf/QUtil.hh>
#include <stdexcept>

namespace docunfold::pdf {
namespace {

std::string Number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6f", v);
  return buf;
}

}  // namespace

QPDFObjectHandle ImageObject(QPDF* pdf, const PageImage& image) {
  QPDFObjectHandle stream = QPDFObjectHandle::newStream(pdf);
  const bool jpeg = image.encoding == PageImage::Encoding::kJpeg;
  QPDFObjectHandle parms = QPDFObjectHandle::newNull();
  if (!jpeg) {
    parms = QPDFObjectHandle::newDictionary();
    parms.replaceKey("/K", QPDFObjectHandle::newInteger(-1));
    parms.replaceKey("/Columns", QPDFObjectHandle::newInteger(image.width));
    parms.replaceKey("/Rows", QPDFObjectHandle::newInteger(image.height));
  }
  stream.replaceStreamData(
      image.data, QPDFObjectHandle::newName(jpeg ? "/DCTDecode" : "/CCITTFaxDecode"), parms);
  QPDFObjectHandle dict = stream.getDict();
  dict.replaceKey("/Type", QPDFObjectHandle::newName("/XObject"));
  dict.replaceKey("/Subtype", QPDFObjectHandle::newName("/Image"));
  dict.replaceKey("/Width", QPDFObjectHandle::newInteger(image.width));
  dict.replaceKey("/Height", QPDFObjectHandle::newInteger(image.height));
  dict.replaceKey("/ColorSpace", QPDFObjectHandle::newName(jpeg ? "/DeviceRGB" : "/DeviceGray"));
  dict.replaceKey("/BitsPerComponent", QPDFObjectHandle::newInteger(jpeg ? 8 : 1));
  return stream;
}

FittedPage FitPage(const fs::path& in, const fs::path& out, double width_pt, double height_pt,
                   const PageImage& image, const DocumentInfo& info) {
  QPDF pdf;
  pdf.setSuppressWarnings(true);
  try {
    pdf.processFile(in.c_str());
    std::vector<QPDFPageObjectHelper> pages = QPDFPageDocumentHelper(pdf).getAllPages();
    if (pages.size() != 1)
      throw std::runtime_error(in.string() + ": expected one page, found " +
                               std::to_string(pages.size()));
    QPDFPageObjectHelper& page = pages.front();
    const QPDFObjectHandle::Rectangle box = page.getMediaBox().getArrayAsRectangle();
    FittedPage fitted;
    fitted.width_pt = width_pt;
    fitted.height_pt = height_pt;
    fitted.scale_x = width_pt / (box.urx - box.llx);
    fitted.scale_y = height_pt / (box.ury - box.lly);
    // Everything the renderer drew (image and text layer) goes through one
    // transform onto the new page.
    page.addPageContents(
        QPDFObjectHandle::newStream(&pdf, "q " + Number(fitted.scale_x) + " 0 0 " +
                                              Number(fitted.scale_y) + " " +
                                              Number(-box.llx * fitted.scale_x) + " " +
                                              Number(-box.lly * fitted.scale_y) + " cm\n"),
        true);
    page.addPageContents(QPDFObjectHandle::newStream(&pdf, "\nQ\n"), false);
    // The image first, under the (invisible) text.
    QPDFObjectHandle resources = page.getObjectHandle().getKey("/Resources");
    if (!resources.isDictionary()) {
      resources = QPDFObjectHandle::newDictionary();
      page.getObjectHandle().replaceKey("/Resources", resources);
    }
    QPDFObjectHandle xobjects = resources.getKey("/XObject");
    if (!xobjects.isDictionary()) {
      xobjects = QPDFObjectHandle::newDictionary();
      resources.replaceKey("/XObject", xobjects);
    }
    xobjects.replaceKey("/PageImage", ImageObject(&pdf, image));
    page.addPageContents(
        QPDFObjectHandle::newStream(&pdf, "q " + Number(width_pt) + " 0 0 " + Number(height_pt) +
                                              " 0 0 cm /PageImage Do Q\n"),
        true);
    page.getObjectHandle().replaceKey(
        "/MediaBox",
        QPDFObjectHandle::newFromRectangle(QPDFObjectHandle::Rectangle(0, 0, width_pt, height_pt)));

    QPDFObjectHandle dict = QPDFObjectHandle::newDictionary();
    dict.replaceKey("/Title", QPDFObjectHandle::newUnicodeString(info.title));
    dict.replaceKey("/Creator", QPDFObjectHandle::newUnicodeString(info.creator));
    dict.replaceKey("/Producer", QPDFObjectHandle::newUnicodeString(info.producer));
    pdf.getTrailer().replaceKey("/Info", pdf.makeIndirectObject(dict));

    QPDFWriter writer(pdf, out.c_str());
    writer.setDeterministicID(true);
    writer.setObjectStreamMode(qpdf_o_generate);
    writer.setCompressStreams(true);
    writer.write();
    return fitted;
  } catch (const std::runtime_error&) {
    throw;
  } catch (const std::exception& e) {
    throw std::runtime_error(std::string("qpdf: ") + e.what());
  }
}

std::string QpdfVersion() { return QPDF::QPDFVersion(); }

}  // namespace docunfold::pdf
